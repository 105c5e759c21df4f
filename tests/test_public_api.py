"""The public API (pokerirl/__init__.py, docs/architecture.md): every name of
``pokerirl.__all__`` resolves to the object of its home module and is documented, and
``import pokerirl`` stays light (no torch) until a name that needs it is read."""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

import pokerirl

ROOT = Path(__file__).resolve().parents[1]

HOME = {  # each public name and the module that defines it
    "Transitions": "pokerirl.irl.transitions",
    "AIRLConfig": "pokerirl.irl.config",
    "train": "pokerirl.irl.adversarial",
    "train_into": "pokerirl.irl.run",
    "load_reward": "pokerirl.irl.run",
    "load_policy": "pokerirl.irl.run",
    "from_imitation_transitions": "pokerirl.irl.interop",
    "to_imitation_transitions": "pokerirl.irl.interop",
    "from_imitation_trajectories": "pokerirl.irl.interop",
    "to_imitation_trajectories": "pokerirl.irl.interop",
    "play_match": "pokerirl.game.match",
    "Agent": "pokerirl.game.bots",
    "load_agent": "pokerirl.agents.checkpoint",
    "resolve_agent": "pokerirl.agents.registry",
    "RLCardAgent": "pokerirl.agents.rlcard_adapter",
    "learned_reward_env": "pokerirl.gym.rewards",
    "load_expert": "pokerirl.gym.expert_policies",
    "Encoding": "pokerirl.game.encodings",
    "get_encoding": "pokerirl.game.encodings",
}


def test_all_is_the_curated_surface() -> None:
    assert sorted(pokerirl.__all__) == sorted(HOME)
    assert len(set(pokerirl.__all__)) == len(pokerirl.__all__)
    assert set(HOME) <= set(dir(pokerirl))


@pytest.mark.parametrize("name", sorted(HOME))
def test_every_public_name_resolves_to_its_home_and_is_documented(name: str) -> None:
    value = getattr(pokerirl, name)
    assert value is getattr(importlib.import_module(HOME[name]), name)
    assert (value.__doc__ or "").strip(), f"pokerirl.{name} has no docstring"
    namespace: dict[str, object] = {}
    exec(f"from pokerirl import {name}", namespace)  # the from-import form works too
    assert namespace[name] is value


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        pokerirl.nope  # noqa: B018


def test_subpackages_list_what_they_export() -> None:
    for package in ("pokerirl.irl", "pokerirl.game", "pokerirl.agents", "pokerirl.gym"):
        module = importlib.import_module(package)
        for name in module.__all__:
            assert getattr(module, name) is not None
    assert {"learned_reward_env", "load_expert"} <= set(
        importlib.import_module("pokerirl.gym").__all__
    )
    assert {"RLCardAgent", "rlcard_states"} <= set(
        importlib.import_module("pokerirl.agents").__all__
    )


@pytest.mark.slow
def test_import_pokerirl_does_not_import_torch() -> None:
    script = (
        "import sys\n"
        "import pokerirl\n"
        "dir(pokerirl), pokerirl.__version__, pokerirl.__all__\n"
        "print(sorted(m for m in ('torch', 'gymnasium', 'pyarrow') if m in sys.modules))\n"
        "pokerirl.load_reward\n"
        "print('torch' in sys.modules)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert done.stdout.splitlines() == ["[]", "True"]  # light, until a name needs torch
