"""The benchmarks' chains: a planar chain of equal links under the levels' gravity, built as a
level so that :class:`~ikgame.physics.world.World` builds it like any other. Its own module, which
imports only the level model, so that older versions of ikgame can build it too
(``benchmarks/versus.py``)."""

from __future__ import annotations

from ikgame.level.model import MAX_LINKS, Level

LINK_PX = 20.0  # length of each link of the benchmark chains


def chain_level(links: int, target: str) -> Level:
    """A planar chain of ``links`` equal links with joint limits, under the levels' gravity (as the
    shipped levels have them), chasing a reach target
    (which it never quite arrives at, so the run does not end) or a circle.

    The level format stops at ``MAX_LINKS``; longer chains are made by validating a legal level
    and copying it with more links (``model_copy`` skips validation), so they are built by the
    very same ``World`` code as any level.
    """
    reach = links * LINK_PX
    if target == "reach":
        step = {"reach": [0.4 * reach, 0.4 * reach], "tolerance": 0.001, "timeout": 600.0}
    else:
        step = {
            "follow": "circle",
            "center": [0.3 * reach, 0.3 * reach],
            "radius": 0.15 * reach,
            "period": 4.0,
            "duration": 600.0,
        }
    link = {
        "length": LINK_PX,
        "mass": 1.0,
        "limits": [-150.0, 150.0],
        "max_torque": 1e9,
        "repeat": min(links, MAX_LINKS),
    }
    level = Level.model_validate(
        {
            "level": {"name": f"{links} links", "duration": 600.0},
            "chain": {"links": [link]},
            "script": [step],
        }
    )
    if links > MAX_LINKS:
        longer = level.chain.links[0].model_copy(update={"repeat": links})
        chain = level.chain.model_copy(update={"links": [longer]})
        level = level.model_copy(update={"chain": chain})
    return level
