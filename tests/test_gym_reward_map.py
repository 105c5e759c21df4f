"""The MountainCar reward map: the preferred action comes from f (argmax over actions, rows
along velocity, columns along position, f averaged over runs), agreement with the real shipped
expert, the CLI's two ways of giving folders, bad inputs, and the same bytes twice."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from pokerirl.cli import app
from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir
from pokerirl.gym.reward_map import plot_reward_map, reward_map
from pokerirl.irl.adversarial import TrainResult
from pokerirl.irl.config import AIRLConfig
from pokerirl.irl.nets import NetSpec, build_nets
from pokerirl.irl.run import save_run

LEFT, NO_PUSH, RIGHT = 0, 1, 2
V_SCALE = 1 / 0.07  # MountainCar's velocity is in [-0.07, 0.07]: k·v in [-1, 1]
BIG = 10.0  # switches a hidden unit off unless its action is taken


def hand_set_run(
    folder: Path,
    *,
    velocity: float = 0.0,
    position: float = 0.0,
    position_at: float = 0.0,
    constant: float = 0.0,
    env: str = "MountainCar-v0",
    algo: str = "hairl",
) -> Path:
    """A run folder (the project's own ``save_run``) whose f is set by hand:

    f(s, right) = relu(velocity·k·v), f(s, left) = relu(−velocity·k·v),
    f(s, no push) = constant + relu(position·(x − position_at)).
    """
    config = AIRLConfig.for_algo(algo, reward_hidden=(4,), policy_hidden=(4,))
    reward, policy = build_nets(NetSpec.of(config), obs_dim=2, action_dim=3, discrete=True)
    with torch.no_grad():
        for p in reward.parameters():
            p.zero_()
        obs_w, bias = reward.obs_layer.weight, reward.obs_layer.bias
        act_w = reward.action_layer.weight
        bias[:] = -BIG
        obs_w[0, 1], act_w[0, RIGHT] = velocity * V_SCALE, BIG  # unit 0: right
        obs_w[1, 1], act_w[1, LEFT] = -velocity * V_SCALE, BIG  # unit 1: left
        act_w[2, NO_PUSH] = BIG + constant  # unit 2: constant for no push
        obs_w[3, 0], act_w[3, NO_PUSH] = position, BIG  # unit 3: no push right of position_at
        bias[3] = -BIG - position * position_at
        reward.head[0].weight[:] = 1.0
    result = TrainResult(reward=reward, policy=policy, config=config, beta_used=0.0)
    save_run(result, folder, algo=algo, data={"env": env})
    return folder


def velocity_rows(result, sign: int) -> np.ndarray:
    """The rows of the map where the velocity has this sign (away from v = 0)."""
    return result.panels[0].preferred[sign * result.ys > 1e-9]


def test_preferred_action_is_the_argmax_of_f_over_actions(tmp_path: Path) -> None:
    # f prefers push right where v > 0 and push left where v < 0, whatever the position.
    run = hand_set_run(tmp_path / "velocity", velocity=1.0)
    result = reward_map("MountainCar-v0", [run], grid=21, expert=None)
    assert result.panels[0].preferred.shape == (21, 21)
    assert result.ys[0] < 0 < result.ys[-1] and result.xs[0] == pytest.approx(-1.2)
    assert (velocity_rows(result, +1) == RIGHT).all()
    assert (velocity_rows(result, -1) == LEFT).all()
    assert result.panels[0].agreement is None and result.expert is None


def test_columns_follow_position_rows_follow_velocity(tmp_path: Path) -> None:
    # A second folder whose f depends on the position only: no push right of x = -0.5, and
    # elsewhere a tie at 0 (argmax takes the first action, push left). A transposed map, or
    # an argmax over the wrong axis, breaks one of the two panels.
    velocity = hand_set_run(tmp_path / "velocity", velocity=1.0)
    position = hand_set_run(tmp_path / "position", position=1.0, position_at=-0.5)
    result = reward_map("MountainCar-v0", [velocity, position], grid=31, expert=None)
    by_position = result.panels[1].preferred
    right_of = result.xs > -0.5 + 1e-9
    assert (by_position[:, right_of] == NO_PUSH).all()
    assert (by_position[:, ~right_of] == LEFT).all()
    assert (velocity_rows(result, +1) == RIGHT).all()


def test_f_is_averaged_over_the_runs_of_a_folder(tmp_path: Path) -> None:
    # run-0 prefers the velocity's direction (|f| up to 1), run-1 no push everywhere (f = 0.5).
    # Mean f: right where k·v > 0.5, left where k·v < -0.5, no push between; a vote would tie.
    hand_set_run(tmp_path / "both" / "run-0", velocity=1.0)
    hand_set_run(tmp_path / "both" / "run-1", constant=0.5)
    result = reward_map("MountainCar-v0", [tmp_path / "both"], grid=40, expert=None)
    kv = result.ys * V_SCALE  # grid 40: no row at k·v = ±0.5, where the mean ties
    expected = np.where(kv > 0.5, RIGHT, np.where(kv < -0.5, LEFT, NO_PUSH))
    assert len(result.panels[0].runs) == 2
    assert (result.panels[0].preferred == expected[:, None]).all()


def test_agreement_with_the_shipped_expert(tmp_path: Path) -> None:
    run = hand_set_run(tmp_path / "velocity", velocity=1.0)
    result = reward_map("MountainCar-v0", [run], grid=25)
    expert = load_expert(resolve_expert_dir("shipped", "MountainCar-v0"))
    # The reference panel is the expert's greedy action, oriented like the reward's map.
    for row, col in ((0, 0), (0, 24), (24, 0), (24, 24), (5, 17)):
        state = np.array([[result.xs[col], result.ys[row]]], dtype=np.float32)
        assert result.expert[row, col] == int(expert.act(state)[0])
    panel = result.panels[0]
    share = float((panel.preferred == result.expert).mean())
    assert panel.agreement == pytest.approx(share)
    assert panel.run_agreements == (pytest.approx(share),)
    assert 0.3 < share < 1  # the expert pushes with the velocity over most of the box
    action, constant = result.constant_agreement
    assert constant == max((result.expert == a).mean() for a in (LEFT, NO_PUSH, RIGHT))
    assert action == result.action_names[int(np.bincount(result.expert.ravel()).argmax())]


def test_cli_takes_runs_a_b_and_repeated_runs_and_writes_the_same_bytes(tmp_path: Path) -> None:
    airl = hand_set_run(tmp_path / "airl" / "run-0", velocity=1.0, algo="airl").parent
    hairl = hand_set_run(tmp_path / "hairl", position=1.0, position_at=-0.5)
    first, second = tmp_path / "maps" / "a.png", tmp_path / "b.png"
    base = ["gym", "reward-map", "MountainCar-v0"]
    result = CliRunner().invoke(
        app, [*base, "--runs", str(airl), str(hairl), "--out", str(first), "--grid", "21"]
    )
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[0].startswith("AIRL: airl (1 run)") and "agrees with the expert on" in lines[0]
    assert lines[1].startswith("H-AIRL: hairl (1 run)")
    assert lines[2].startswith("baseline: a constant")
    again = CliRunner().invoke(
        app, [*base, "--runs", str(airl), "--runs", str(hairl), "-o", str(second), "--grid", "21"]
    )
    assert again.exit_code == 0, again.output
    assert again.output.splitlines()[:3] == lines[:3]
    assert first.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert first.read_bytes() == second.read_bytes()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["Acrobot-v1", "--runs", "{good}"], "needs a 2-d observation and discrete actions"),
        (["MountainCar-v0", "--runs", "{good}", "{missing}"], "missing: no such folder"),
        (["MountainCar-v0", "--runs", "{acrobot}"], "a run on Acrobot-v1, not MountainCar-v0"),
        (["MountainCar-v0", "--runs", "{poker}"], "not a Gymnasium IRL run"),
        (["MountainCar-v0", "--runs", "{empty}"], "not an IRL run folder"),
        (["MountainCar-v0"], "give the IRL folders"),
    ],
)
def test_cli_bad_input_fails_in_one_line_and_keeps_the_old_map(
    tmp_path: Path, args: list[str], message: str
) -> None:
    folders = {
        "good": hand_set_run(tmp_path / "good", velocity=1.0),
        "acrobot": hand_set_run(tmp_path / "acrobot", env="Acrobot-v1"),
        "poker": hand_set_run(tmp_path / "poker", env=None),  # type: ignore[arg-type]
        "empty": tmp_path / "empty",
        "missing": tmp_path / "missing",
    }
    folders["empty"].mkdir()
    out = tmp_path / "map.png"
    out.write_bytes(b"an earlier map")
    args = [a.format(**{k: str(v) for k, v in folders.items()}) for a in args]
    result = CliRunner().invoke(app, ["gym", "reward-map", *args, "--out", str(out)])
    assert result.exit_code != 0
    assert message in result.output
    assert len(result.output.strip().splitlines()) == 1, result.output
    assert out.read_bytes() == b"an earlier map"


def test_plot_bytes_change_with_the_map(tmp_path: Path) -> None:
    # The same bytes twice is not vacuous: another map gives other bytes.
    a = reward_map("MountainCar-v0", [hand_set_run(tmp_path / "a", velocity=1.0)], grid=11,
                   expert=None)  # fmt: skip
    b = reward_map("MountainCar-v0", [hand_set_run(tmp_path / "b", velocity=-1.0)], grid=11,
                   expert=None)  # fmt: skip
    paths = [plot_reward_map(r, tmp_path / f"{i}.png") for i, r in enumerate((a, a, b))]
    assert paths[0].read_bytes() == paths[1].read_bytes() != paths[2].read_bytes()


def test_the_drawing_puts_positive_velocity_on_top(tmp_path: Path) -> None:
    from matplotlib.image import imread

    result = reward_map("MountainCar-v0", [hand_set_run(tmp_path / "v", velocity=1.0)],
                        grid=21, expert=None)  # fmt: skip
    pixels = imread(plot_reward_map(result, tmp_path / "map.png"))[..., :3]

    def rows_of(colour: str) -> np.ndarray:
        rgb = np.array([int(colour[i : i + 2], 16) / 255 for i in (1, 3, 5)])
        return np.nonzero(np.abs(pixels - rgb).max(-1) < 0.02)[0]

    right, left = rows_of("#D55E00"), rows_of("#0072B2")  # push right, push left
    assert len(right) > 1000 and len(left) > 1000
    assert right.mean() < left.mean()  # image rows grow downwards
