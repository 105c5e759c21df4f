"""The runnable examples of docs/examples/ run, at tiny sizes, in their own processes: each
exits 0 and prints its ``result:`` line(s). A new example needs an entry in EXAMPLES."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES_DIR = ROOT / "docs" / "examples"

# Each example with the arguments that make it tiny, and the result line it must print.
EXAMPLES = {
    "airl_gym_rollouts.py": (
        ["--episodes", "3", "--epochs", "1"],
        r"^result: hairl on \d+ transitions from 3 episodes, 1 epochs: policy alignment 0\.\d+",
    ),
    "learned_reward_sb3.py": (
        ["--episodes", "2", "--epochs", "1", "--steps", "256"],
        r"^result: PPO on the learned reward, 256 steps: true return \d+\.\d",
    ),
    "own_poker_agent.py": (
        ["--hands", "200"],
        r"^result: pairs-and-aces vs tightbot: [+-]\d+ ± \d+ mbb/h over 200 hands$",
    ),
    "agent_in_rlcard.py": (
        ["--agent", "call", "--hands", "50"],
        r"^result: call vs RLCard's RandomAgent in RLCard, 50 hands: [+-]\d+\.\d{3} big blinds",
    ),
}


def test_every_example_is_listed() -> None:
    assert sorted(p.name for p in EXAMPLES_DIR.glob("*.py")) == sorted(EXAMPLES)


# Over 15 s on a loaded machine (PPO, an RLCard match, gym rollouts): not in `make test-fast`.
SLOW_EXAMPLES = {"learned_reward_sb3.py", "agent_in_rlcard.py", "airl_gym_rollouts.py"}


@pytest.mark.parametrize(
    "name",
    [
        pytest.param(n, marks=pytest.mark.slow) if n in SLOW_EXAMPLES else n
        for n in sorted(EXAMPLES)
    ],
)
def test_example_runs_and_prints_its_result(name: str, tmp_path: Path) -> None:
    arguments, result = EXAMPLES[name]
    # This checkout's pokerirl, whatever is installed; run from elsewhere, as a reader would.
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}  # fmt: skip
    done = subprocess.run(
        [sys.executable, str(EXAMPLES_DIR / name), *arguments],
        capture_output=True, text=True, cwd=tmp_path, env=environment, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert any(re.search(result, line) for line in done.stdout.splitlines()), done.stdout
