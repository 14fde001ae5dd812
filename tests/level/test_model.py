"""The level model's start-up cost: its validators are built when a level is first validated."""

import subprocess
import sys

_BUILT = """
from pydantic import BaseModel

import ikgame.level.model as model

models = [
    value
    for value in vars(model).values()
    if isinstance(value, type) and issubclass(value, BaseModel) and value.__module__ == model.__name__
]
print(sorted(m.__name__ for m in models if m.__pydantic_complete__))
from ikgame.level import DEFAULT_LEVEL
from ikgame.level.loader import load_level

load_level(DEFAULT_LEVEL)
print(model.Level.__pydantic_complete__, len(models))
"""


def test_importing_the_model_builds_no_validator_and_loading_a_level_builds_the_level(tmp_path):
    # A run validates one Level, whose build covers every nested model: building each model
    # on its own at import as well would only add to every command's start-up.
    proc = subprocess.run(
        [sys.executable, "-c", _BUILT], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    at_import, after_load = proc.stdout.splitlines()
    assert at_import == "[]"
    built, count = after_load.split()
    assert built == "True" and int(count) > 20
