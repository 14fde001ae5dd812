"""The compiled motor loops of long chains: the space left exactly as the Python loops leave it,
and a run the same with numba or without it."""

from __future__ import annotations

import numpy as np
import pymunk
import pytest

from ikgame.level.model import Level
from ikgame.physics import _motors
from ikgame.physics.world import SWEEP_LINKS, World

pytest.importorskip("numba", reason="the compiled path needs the 'fast' extra")


def _level(links: int, step: dict[str, object] | None = None) -> Level:
    return Level.model_validate(
        {
            "level": {"name": "long", "duration": 5.0},
            "world": {"gravity": [0.0, -900.0]},
            "chain": {
                "angle": 30.0,
                "links": [
                    {"length": 8.0, "limits": [-150.0, 150.0], "max_torque": 4e4, "repeat": links}
                ],
            },
            "script": [step or {"wait": 1.0}],
        }
    )


def _state(world: World) -> list[float]:
    bodies = [(*b.position, b.angle, *b.velocity, b.angular_velocity) for b in world.bodies]
    motors = [(m.rate, m.max_force, m.impulse) for m in world.motors + world._returns]
    return [v for row in bodies + motors for v in row]


def test_compiled_motors_leave_the_space_as_the_python_loops_do() -> None:
    links = SWEEP_LINKS + 20
    compiled, python = World(_level(links)), World(_level(links))
    assert compiled._compiled is not None
    python._compiled = None
    rng = np.random.default_rng(11)
    limited = []
    for _ in range(30):
        # Rates and loads as a servo gives them: budgets what the torques leave, some none;
        # rates far off, so that motors run into their budgets.
        rates = rng.uniform(-30.0, 30.0, links)
        torques = rng.uniform(-5e4, 5e4, links)
        forces = rng.uniform(-500.0, 500.0, (links, 2))
        budgets = np.maximum(compiled.max_torque - np.abs(torques), 0.0)
        for world in (compiled, python):
            world.joint_state()
            world.drive(rates, torques, forces, budgets)
            world.step(1 / 240)
        assert _state(compiled) == _state(python)
        assert compiled.motor_torques().tolist() == python.motor_torques().tolist()
        assert compiled.torque_limited().tolist() == python.torque_limited().tolist()
        limited.append(python.torque_limited())
    assert 0 < np.count_nonzero(limited) < np.size(limited)


def test_chains_without_the_return_sweep_and_a_turned_off_switch_stay_in_python(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    assert World(_level(SWEEP_LINKS))._compiled is None
    assert World(_level(SWEEP_LINKS + 1))._compiled is not None
    monkeypatch.setenv("IKGAME_COMPILED", "0")
    assert World(_level(SWEEP_LINKS + 1))._compiled is None


def test_compiled_motors_check_their_inputs() -> None:
    world = World(_level(SWEEP_LINKS + 1))
    assert world._compiled is not None
    motors, _ = world._compiled
    with pytest.raises(ValueError, match="expected"):
        motors.write(np.zeros(3), np.zeros(SWEEP_LINKS + 1))


def test_a_numba_that_cannot_compile_leaves_the_motors_in_python(
    numba_without_compiler: str,
) -> None:
    _motors._kernels.cache_clear()
    try:
        with pytest.warns(RuntimeWarning, match=numba_without_compiler):
            assert _motors._kernels() is None
        assert World(_level(SWEEP_LINKS + 1))._compiled is None
    finally:
        _motors._kernels.cache_clear()


def test_a_motor_written_compiled_reads_back_as_pymunk_sees_it() -> None:
    space = pymunk.Space()
    a, b = pymunk.Body(body_type=pymunk.Body.KINEMATIC), pymunk.Body(1.0, 1.0)
    motor = pymunk.SimpleMotor(a, b, 0.0)
    space.add(a, b, motor)
    compiled = _motors.compiled_motors([motor._constraint])
    assert compiled is not None
    compiled.write(np.array([1.25]), np.array([7.5]))
    assert (motor.rate, motor.max_force) == (-1.25, 7.5)
    space.step(0.01)
    assert compiled.impulses().tolist() == [motor.impulse]


def test_a_long_chains_run_is_the_same_compiled_or_not(monkeypatch: pytest.MonkeyPatch) -> None:
    from ikgame.sim import Simulation

    def run() -> list[float]:
        level = _level(SWEEP_LINKS + 10, {"reach": [300.0, 400.0], "timeout": 5.0})
        sim = Simulation(level, record=False)
        for _ in range(20):
            sim.step()
        return [*_state(sim.world), *sim.world.motor_torques().tolist()]

    compiled = run()
    monkeypatch.setenv("IKGAME_COMPILED", "0")
    assert run() == compiled
