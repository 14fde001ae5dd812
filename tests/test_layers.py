"""The one-way data flow, checked on the imports: pure math stays pure, physics never draws."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "ikgame"

FORBIDDEN = {
    "kinematics": {
        "pymunk",
        "PIL",
        "ikgame.physics",
        "ikgame.render",
        "ikgame.sim",
        "ikgame.level",
    },
    "level": {"pymunk", "PIL", "ikgame.physics", "ikgame.render", "ikgame.sim"},
    "physics": {"PIL", "ikgame.render", "ikgame.sim", "ikgame.control"},
    "control": {"pymunk", "PIL", "ikgame.physics", "ikgame.render", "ikgame.sim"},
    # Sprites reach the renderer decoded, in the Scene: it never reads a level or its files.
    "render": {"ikgame.sim", "ikgame.physics", "ikgame.control", "ikgame.level", "ikgame.skins"},
}


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
    return names


@pytest.mark.parametrize("layer", sorted(FORBIDDEN))
def test_layer_imports_nothing_downstream(layer):
    for path in sorted((PACKAGE / layer).glob("*.py")):
        for name in _imports(path):
            for banned in FORBIDDEN[layer]:
                assert not (name == banned or name.startswith(banned + ".")), (path.name, name)
