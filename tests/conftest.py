"""Shared test helpers: small levels built in code."""

from __future__ import annotations

import copy

import pytest

from ikgame.level.model import Level

_BASE = {
    "level": {"name": "test", "duration": 6.0},
    "world": {"gravity": [0.0, -900.0]},
    "chain": {
        "links": [{"length": 100.0, "mass": 1.0, "max_torque": 4.0e6, "repeat": 3}],
    },
    "script": [{"reach": [150.0, 150.0]}],
}


def _merge(base: dict, changes: dict) -> dict:
    out = copy.deepcopy(base)
    for key, value in changes.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


@pytest.fixture
def make_level():
    """``make_level(chain={...}, script=[...])``: a small valid level with the given changes."""

    def make(**changes: object) -> Level:
        return Level.model_validate(_merge(_BASE, changes))

    return make
