"""Lazy re-exports: every package name resolves to its module's object, and the names listed for
type checkers are the names served at run time."""

import ast
import importlib
from pathlib import Path

import pytest

from ikgame._lazy import lazy_exports

PACKAGES = ["ikgame", "ikgame.level", "ikgame.render"]


def _type_checking_imports(package: str) -> dict[str, str]:
    """Name -> module of the imports under ``if TYPE_CHECKING:`` in the package's __init__."""
    path = Path(importlib.import_module(package).__file__)
    names = {}
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            for stmt in node.body:
                names.update({alias.name: stmt.module for alias in stmt.names})
    return names


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_name_resolves_and_matches_the_static_imports(package):
    module = importlib.import_module(package)
    static = _type_checking_imports(package)
    assert sorted(static) == module.__all__
    for name, home in static.items():
        assert getattr(module, name) is getattr(importlib.import_module(home), name)
    assert set(module.__all__) <= set(dir(module))


def test_unknown_names_raise_attribute_error():
    _, getattr_, _ = lazy_exports("ikgame", {"ikgame.snapshot": ["Scene"]})
    with pytest.raises(AttributeError, match="has no attribute 'Nope'"):
        getattr_("Nope")
    import ikgame

    with pytest.raises(AttributeError):
        ikgame.Nope  # noqa: B018
