"""ikgame: a 2D physics sandbox for procedural animation.

A motorised pymunk chain is driven each tick by an inverse-kinematics controller toward targets
that a level script sets, and the run is rendered headless with Pillow.
"""

__version__ = "0.1.0"
