"""Task presets: consistent data, real environment ids, and the study presets' budgets."""

from __future__ import annotations

from pathlib import Path

import pytest

from pokerirl.gym.presets import TASK_ORDER, TASKS, PPOSettings, RLSettings
from pokerirl.studies.gym.config import PRESETS


def test_every_task_is_a_registered_environment_with_the_declared_action_space(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("gymnasium")
    monkeypatch.chdir(tmp_path)  # MuJoCo writes its warnings to MUJOCO_LOG.TXT in the cwd
    from pokerirl.gym.envs import make_env

    assert sorted(TASK_ORDER) == sorted(TASKS)
    for env_id, task in TASKS.items():
        env = make_env(env_id)
        assert hasattr(env.action_space, "n") == task.discrete, env_id
        env.close()
    # The paper's versions where Gymnasium 1.x still has them (LunarLander-v2 is gone).
    assert {"Ant-v4", "HalfCheetah-v4", "LunarLander-v3"} <= set(TASKS)


def test_rl_settings_need_exactly_their_algorithms_settings() -> None:
    ppo = TASKS["Acrobot-v1"].rl.ppo
    with pytest.raises(ValueError, match="exactly its own settings"):
        RLSettings(algo="dqn", timesteps=1, ppo=ppo)
    with pytest.raises(ValueError, match="exactly its own settings"):
        RLSettings(algo="ppo", timesteps=1)
    assert isinstance(ppo, PPOSettings) and ppo.n_epochs == 20


def test_quick_preset_shrinks_budgets_and_keeps_the_authors_method_settings() -> None:
    quick, paper = PRESETS["quick"], PRESETS["paper"]
    assert quick.tasks == ("MountainCar-v0",) and quick.runs == 3
    irl, authors = quick.irl("MountainCar-v0"), TASKS["MountainCar-v0"].irl
    assert irl.transitions < authors.transitions and irl.epochs < authors.epochs
    assert (irl.alpha, irl.beta, irl.sigma_start, irl.sigma_end, irl.learning_rate) == (
        authors.alpha, authors.beta, authors.sigma_start, authors.sigma_end, authors.learning_rate,
    )  # fmt: skip
    assert quick.rl("MountainCar-v0").timesteps < TASKS["MountainCar-v0"].rl.timesteps
    assert quick.rl("MountainCar-v0").dqn == TASKS["MountainCar-v0"].rl.dqn
    for env_id in paper.tasks:
        assert paper.irl(env_id) == TASKS[env_id].irl and paper.rl(env_id) == TASKS[env_id].rl


@pytest.mark.slow
def test_importing_the_gym_package_and_the_cli_does_not_import_gymnasium_or_sb3() -> None:
    # A poker-only user must not pay for the gym extra (nor need it installed).
    import subprocess
    import sys

    code = (
        "import sys, pokerirl.cli, pokerirl.gym.presets, pokerirl.gym.expert_policies, "
        "pokerirl.gym.collect, pokerirl.gym.rewards, pokerirl.gym.rl\n"
        "loaded = {'gymnasium', 'stable_baselines3', 'mujoco'} & set(sys.modules)\n"
        "assert not loaded, loaded"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


# What a light command must not load: torch alone is about 2 s and 600 MB (issue 34); scipy
# about 1 s. The reports are the committed results: a gym study, a poker study, a tournament.
HEAVY = ("torch", "gymnasium", "stable_baselines3", "pyarrow", "mujoco", "scipy")
RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"
LIGHT_COMMANDS = (
    ["--help"],
    ["version"],
    ["gym", "--help"],
    ["gym", "experts"],
    ["gym", "experts", "--format", "json"],
    ["report", str(RESULTS / "mountaincar-paper10")],
    ["report", str(RESULTS / "study-quick-strength"), "--format", "json"],
    # A report of today's format stores its test across training seeds; one of the /1 format
    # (docs/results/study-quick-strength/tournament) has it derived on reading, and that t-test
    # imports scipy (tests/test_tournament_replication.py reads it).
    ["report", str(RESULTS / "poker-real" / "study-real-test" / "tournament")],
)


def test_light_commands_import_no_torch_gymnasium_sb3_or_pyarrow() -> None:
    # Each command runs in one fresh interpreter, in turn; the first to load a heavy package
    # is named. `gym experts` only prints the manifest (pokerirl.gym.manifest).
    import json
    import subprocess
    import sys

    code = (
        "import json, sys\n"
        "from typer.testing import CliRunner\n"
        "from pokerirl.cli import app\n"
        f"heavy, found = {HEAVY!r}, {{}}\n"
        f"for args in {LIGHT_COMMANDS!r}:\n"
        "    result = CliRunner().invoke(app, args)\n"
        "    assert result.exit_code == 0, (args, result.output)\n"
        "    found[' '.join(args)] = sorted(h for h in heavy if h in sys.modules)\n"
        "print(json.dumps(found))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    found = json.loads(done.stdout.splitlines()[-1])
    assert list(found) == [" ".join(args) for args in LIGHT_COMMANDS]
    assert all(loaded == [] for loaded in found.values()), found


def test_gymnasium_tasks_use_no_reward_weight_decay_as_the_authors() -> None:
    # Issue 20: the poker default 5e-3 used to leak into every Gymnasium run.
    from pokerirl.gym.irl import irl_config

    for task in TASKS.values():
        assert task.irl.reward_weight_decay == 0.0
        for algo in ("airl", "hairl"):
            assert irl_config(algo, task.irl, seed=0).reward_weight_decay == 0.0
