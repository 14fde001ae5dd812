"""Trees and creatures in the level format: named bones, effectors, the gait, and chains that
load exactly as they did before trees existed."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ikgame.level.library import LEVELS_DIR
from ikgame.level.loader import LevelError, load_level, parse_level
from ikgame.level.model import MAX_LINKS, ChainConfig, GaitConfig, Level
from ikgame.level.script import ScriptRunner

ROOT = Path(__file__).resolve().parents[2]
TREES = sorted((ROOT / "tests" / "data" / "levels" / "trees").glob("*.toml"))
STRESS = sorted((ROOT / "benchmarks" / "stress_levels").glob("*.toml"))
# The shipped and stress levels given as chains of links (the tree levels give bones).
CHAINS = [
    path
    for path in (*sorted(LEVELS_DIR.glob("*.toml")), *STRESS)
    if "[[chain.bones]]" not in path.read_text(encoding="utf-8")
]
HEAD = '[level]\nname = "t"\nduration = 2.0\n[chain]\n'


def _problems(text: str) -> list[str]:
    with pytest.raises(LevelError) as exc:
        parse_level(text, "t.toml")
    return [str(p) for p in exc.value.problems]


def _bone(name: str, parent: str | None = None, **fields: object) -> str:
    lines = ["[[chain.bones]]", f'name = "{name}"', "length = 40.0"]
    lines += [f'parent = "{parent}"'] if parent else []
    lines += [f"{key} = {json.dumps(value)}" for key, value in fields.items()]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("path", TREES, ids=[p.stem for p in TREES])
def test_tree_level_loads_to_its_pinned_model(path):
    expected = json.loads(path.with_suffix(".expected.json").read_text(encoding="utf-8"))
    assert load_level(path).model_dump(mode="json", by_alias=True) == expected


def test_bones_expand_parents_first_with_repeats_in_a_row():
    chain = load_level(ROOT / "tests/data/levels/trees/two_arms.toml").chain
    links = chain.expanded_links
    assert [(k.name, k.parent_index, k.source) for k in links] == [
        ("torso", -1, 0),
        ("left.1", 0, 1),
        ("left", 1, 1),
        ("right.1", 0, 2),
        ("right", 3, 2),
    ]
    assert chain.effector_names == ("left", "right")
    assert chain.effector_links == (2, 4)
    assert [k.weight for k in links if k.effector] == [1.0, 2.0]
    assert [k.angle for k in links] == [0.0, 60.0, 60.0, -60.0, -60.0]


def test_a_creature_has_several_roots_each_at_its_hip_and_legs_the_script_leaves_alone():
    level = load_level(ROOT / "tests/data/levels/trees/walker.toml")
    roots = [k for k in level.chain.expanded_links if k.parent_index < 0]
    assert [k.at for k in roots] == [
        (50.0, 0.0),
        (25.0, 0.0),
        (-25.0, 0.0),
        (-50.0, 0.0),
        (60.0, 10.0),
    ]
    assert level.script_effectors == ("head",)
    assert level.gait.step_groups == (("front_foot", "back_foot"), ("front2_foot", "back2_foot"))
    assert level.gait.step_threshold == 30.0
    # angle 0 points the body's x forward: a hip at at = [50, 0] hangs its leg straight down.
    hip, knee = np.array(level.chain.start_segments()[:2])
    assert hip == pytest.approx(np.array([[50.0, 110.0], [50.0, 55.0]]))
    assert knee == pytest.approx(np.array([[50.0, 55.0], [50.0, 5.0]]))


def test_at_is_in_the_base_frame_which_turns_with_chain_angle():
    text = HEAD + "base = [10.0, 20.0]\nangle = 90.0\n" + _bone("a", at=[30.0, 5.0])
    chain = parse_level(text + _bone("b", at=[0.0, 0.0]) + "[[script]]\nwait = 1.0\n").chain
    # x along the mount (up), y to its left (-x).
    assert np.array(chain.start_segments()[0]) == pytest.approx(
        np.array([[5.0, 50.0], [5.0, 90.0]])
    )


def test_a_start_angle_is_clipped_only_when_left_at_its_default():
    text = HEAD + _bone("a", limits=[20.0, 90.0]) + _bone("b", "a", angle=-30.0)
    chain = parse_level(text + "[[script]]\nwait = 1.0\n").chain
    (a0, a1), (b0, b1) = chain.start_segments()
    up = math.radians(90.0 + 20.0)
    assert a1 == pytest.approx((40.0 * math.cos(up), 40.0 * math.sin(up)))
    turn = up - math.radians(30.0)
    assert b1 == pytest.approx((a1[0] + 40.0 * math.cos(turn), a1[1] + 40.0 * math.sin(turn)))


def test_an_inner_bone_may_be_an_effector_and_a_leaf_may_not():
    text = HEAD + _bone("arm", effector=True, weight=3.0) + _bone("hand", "arm", effector=False)
    level = parse_level(text + "[[script]]\nreach = { arm = [0.0, 40.0] }\n")
    assert level.chain.effector_names == ("arm",)
    assert level.chain.expanded_links[0].weight == 3.0
    assert _problems(text + "[[script]]\nreach = { hand = [0.0, 40.0] }\n") == [
        "t.toml:16: script[0].reach.hand: no effector is named 'hand' (effectors: 'arm')"
    ]


def test_a_repeated_bone_keeps_its_name_for_its_last_link_and_its_children():
    text = HEAD + _bone("spine", repeat=3) + _bone("head", "spine", mass=2.0)
    chain = parse_level(text + "[[script]]\nwait = 1.0\n").chain
    assert [(k.name, k.parent_index) for k in chain.expanded_links] == [
        ("spine.1", -1),
        ("spine.2", 0),
        ("spine", 1),
        ("head", 2),
    ]


def test_a_tree_with_one_effector_takes_a_point_and_unnamed_steps():
    text = HEAD + _bone("upper") + _bone("fore", "upper")
    level = parse_level(
        text + "[[script]]\nreach = [0.0, 70.0]\n"
        '[[script]]\nfollow = "line"\nfrom = [0.0, 70.0]\nto = [20.0, 60.0]\nduration = 1.0\n'
    )
    assert level.script_effectors == ("fore",)


def test_the_size_limits_count_bones_after_repeat():
    text = HEAD + _bone("a", repeat=MAX_LINKS) + _bone("b", "a") + "[[script]]\nwait = 1.0\n"
    assert _problems(text) == [
        "t.toml:5: chain.bones: a tree has at most 200 links, this one has 201"
    ]


def test_every_problem_of_a_bone_points_at_its_line():
    text = HEAD + _bone("a") + _bone("b", "a") + _bone("c", "x") + "[[script]]\nwait = 1.0\n"
    assert _problems(text) == [
        "t.toml:15: chain.bones[2].parent: no bone is named 'x' (bones: 'a', 'b', 'c')"
    ]


def test_a_long_list_of_names_in_a_message_is_cut_short():
    bones = "".join(_bone(f"b{i}", f"b{i - 1}" if i else None) for i in range(12))
    text = HEAD + bones + "[[script]]\nreach = { nope = [0.0, 1.0] }\n"
    (problem,) = _problems(text)
    assert problem.endswith("no effector is named 'nope' (effectors: 'b11')")
    text = HEAD + bones + _bone("c", "zz") + "[[script]]\nwait = 1.0\n"
    (problem,) = _problems(text)
    assert "'b8', 'b9', ...)" in problem and "'b10'" not in problem


def test_a_set_step_may_turn_the_base_and_over_applies_to_the_turn():
    text = HEAD + "[[chain.links]]\nlength = 40.0\n"
    level = parse_level(
        text + "[[script]]\nset = { angle = 45.0, over = 2.0 }\n[[script]]\nwait = 1.0\n"
    )
    assert level.script[0].set.angle == 45.0 and level.script[0].set.moves_base
    assert _problems(text + "[[script]]\nset = { angle = 181.0 }\n[[script]]\nwait = 1.0\n") == [
        "t.toml:8: script[0].set.angle: Input should be less than or equal to 180 (got 181.0)"
    ]


@pytest.mark.parametrize(
    ("legs", "groups"),
    [
        (["a"], (("a",),)),
        (["a", "b"], (("a",), ("b",))),
        (["a", "b", "c", "d"], (("a", "c"), ("b", "d"))),
        (["a", "b", "c", "d", "e", "f"], (("a", "c", "e"), ("b", "d", "f"))),
    ],
)
def test_gait_groups_default_to_legs_alternating_front_to_back(legs, groups):
    assert GaitConfig(legs=legs).step_groups == groups


def test_gait_groups_as_given_and_threshold_as_given():
    gait = GaitConfig(legs=["a", "b", "c"], groups=[["c"], ["a", "b"]], threshold=12.0)
    assert gait.step_groups == (("c",), ("a", "b"))
    assert gait.step_threshold == 12.0


def _as_bones(text: str) -> str:
    """A chain level's text with each ``[[chain.links]]`` entry written as a bone hanging from
    the one before it."""
    out, count = [], 0
    for line in text.splitlines():
        if line.strip() == "[[chain.links]]":
            out += ["[[chain.bones]]", f'name = "b{count}"']
            out += [f'parent = "b{count - 1}"'] if count else []
            count += 1
        else:
            out.append(line)
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("path", CHAINS, ids=[p.stem for p in CHAINS])
def test_every_chain_loads_as_a_chain_and_as_the_same_tree_of_bones(path):
    text = path.read_text(encoding="utf-8")
    chain = parse_level(text).chain
    links = chain.expanded_links
    assert [k.parent_index for k in links] == list(range(-1, len(links) - 1))
    assert chain.effector_names == ("tip",)
    assert chain.effector_links == (len(links) - 1,)
    assert [k.effector for k in links] == [False] * (len(links) - 1) + [True]
    tree = parse_level(_as_bones(text)).chain
    assert _physical(tree) == _physical(chain)
    assert tree.start_segments() == chain.start_segments()


def _physical(chain: ChainConfig) -> list[tuple]:
    return [
        (k.parent_index, k.length, k.mass, k.width, k.limits, k.max_torque, k.max_speed)
        for k in chain.expanded_links
    ]


_LINK = st.fixed_dictionaries(
    {"length": st.floats(1.0, 300.0), "repeat": st.integers(1, 5)},
    optional={
        "mass": st.floats(0.5, 5.0),
        "limits": st.tuples(st.floats(-180.0, -1.0), st.floats(1.0, 180.0)),
    },
)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(links=st.lists(_LINK, min_size=1, max_size=6), angle=st.floats(-180.0, 180.0))
def test_a_chain_written_as_bones_is_the_same_chain(links, angle):
    chain = ChainConfig(angle=angle, links=links)
    bones = [
        {**link, "name": f"b{i}", **({"parent": f"b{i - 1}"} if i else {})}
        for i, link in enumerate(links)
    ]
    tree = ChainConfig(angle=angle, bones=bones)
    assert _physical(tree) == _physical(chain)
    assert tree.start_segments() == chain.start_segments()
    assert tree.effector_links == chain.effector_links
    assert tree.effector_names == (f"b{len(links) - 1}",)


def test_start_segments_of_a_chain_are_its_links_end_to_end_at_their_clipped_zero_angles():
    for path in CHAINS:
        chain = load_level(path).chain
        angle, joint = math.radians(chain.angle), chain.base
        for link, (start, end) in zip(chain.expanded_links, chain.start_segments(), strict=True):
            low, high = link.limits or (0.0, 0.0)
            angle += math.radians(min(max(0.0, low), high))
            tip = (
                joint[0] + link.length * math.cos(angle),
                joint[1] + link.length * math.sin(angle),
            )
            assert (start, end) == (joint, tip), path.name
            joint = tip


def test_the_level_model_doctest_chain_is_still_a_chain():
    level = Level.model_validate(
        {
            "level": {"name": "x", "duration": 1.0},
            "chain": {"links": [{"length": 50.0, "repeat": 2}]},
            "script": [{"reach": [50.0, 50.0]}],
        }
    )
    assert level.chain.bones is None and level.chain.entry_field == "links"
    assert level.script_effectors == ("tip",)


def test_a_reach_step_with_an_effector_key_is_shown_the_table():
    text = HEAD + "[[chain.links]]\nlength = 40.0\n[[script]]\nreach = [0.0, 40.0]\n"
    assert _problems(text + 'effector = "tip"\n') == [
        "t.toml:9: script[0].effector: a reach step names its effectors in a table: "
        "reach = { name = [x, y] }"
    ]


def test_a_changed_copy_of_a_chain_expands_its_own_links():
    chain = ChainConfig(links=[{"length": 10.0, "repeat": 3}])
    assert len(chain.expanded_links) == 3
    longer = chain.model_copy(update={"links": [chain.links[0].model_copy(update={"repeat": 7})]})
    assert len(longer.expanded_links) == 7 and len(chain.expanded_links) == 3
    assert longer.effector_links == (6,)


@pytest.mark.parametrize("path", TREES, ids=[p.stem for p in TREES])
def test_a_tree_level_plays_through_its_script_when_every_effector_is_on_its_target(path):
    level = load_level(path)
    runner = ScriptRunner(level.script, level.script_effectors)
    dt, tick, changes = 1.0 / level.world.tick_rate, 0, []
    while not runner.done and tick * dt < level.level.duration:
        targets = runner.targets
        changes += runner.take_changes()
        tick += 1
        runner.observe(tick * dt, dt, targets)
    outcomes = runner.finish(tick * dt)
    assert all(o.passed for o in outcomes), [(o.index, o.note) for o in outcomes]
    scored = [o for o in outcomes if o.kind in ("reach", "follow")]
    assert scored and all(set(o.effectors) <= set(level.script_effectors) for o in scored)
    # A follow step's target moves on after each tick's read, a reach step's stays put.
    assert all(o.final_error == 0.0 for o in scored if o.kind == "reach")
    assert [bool(c.moves_base) for c in changes] == [
        s.set.moves_base for s in level.script if hasattr(s, "set")
    ]


def test_branches_collide_is_for_trees_only():
    problems = _problems(
        HEAD
        + "branches_collide = true\n[[chain.links]]\nlength = 10.0\n"
        + "[[script]]\nwait = 1.0\n"
    )
    assert any("branches_collide" in p and "no branches" in p for p in problems), problems
