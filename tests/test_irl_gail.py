"""GAIL beside AIRL: the discriminator strategies, the algorithm's settings, training on a
toy poker table and a tiny Gymnasium table, and the commands (issue 35 item 1)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import torch
from testkit import Cli

from pokerirl.datasets.toy import toy_expert_table
from pokerirl.errors import ConfigError
from pokerirl.irl import AIRLConfig, discriminator_loss, fast, load_config, train
from pokerirl.irl.config import ALGOS
from pokerirl.irl.discriminators import AIRL, GAIL, discriminator_for
from pokerirl.poker import transitions_from_arrow

torch.set_num_threads(1)

CLI = Cli()  # pokerirl run in this process (tests/testkit.py)


def test_the_discriminators_give_their_logits_on_known_numbers() -> None:
    f, log_pi = torch.tensor([0.0, 1.0]), torch.log(torch.tensor([0.5, 0.25]))
    # AIRL: log D − log(1 − D) = f − log π; D = exp f / (exp f + π)
    torch.testing.assert_close(AIRL.logits(f, log_pi), torch.tensor([math.log(2), 1 + math.log(4)]))
    d = torch.sigmoid(AIRL.logits(f, log_pi))
    torch.testing.assert_close(d, f.exp() / (f.exp() + log_pi.exp()))
    # GAIL: the logit is f, whatever π
    torch.testing.assert_close(GAIL.logits(f, log_pi), f)
    assert discriminator_for("airl") is AIRL and discriminator_for("gail") is GAIL
    # their losses: at f = 0 GAIL's D is 1/2 whatever π (2 ln 2); AIRL's is not
    zero, half = torch.zeros(1), torch.log(torch.tensor([0.5]))
    gail = discriminator_loss(zero, half, zero, half, discriminator=GAIL)[0].item()
    airl = discriminator_loss(zero, half, zero, half)[0].item()
    assert gail == pytest.approx(2 * math.log(2))
    assert airl == pytest.approx(-math.log(2 / 3) - math.log(1 / 3))  # D = 2/3 on both rows


@pytest.mark.parametrize("beta", [0.0, 0.4])
def test_gails_hand_derived_gradient_is_autograds(beta: float) -> None:
    torch.manual_seed(0)
    f = torch.randn(12, requires_grad=True)
    log_pi = torch.log(torch.rand(12) * 0.9 + 0.05)
    env = torch.randn(6) if beta else None
    weights = torch.rand(6) + 0.5
    loss = discriminator_loss(f[:6], log_pi[:6], f[6:], log_pi[6:], beta=beta, env_reward=env,
                              weights=weights, discriminator=GAIL)[0]  # fmt: skip
    loss.backward()
    grad = fast.discriminator_grad(f.detach(), log_pi, beta=beta, env_reward=env,
                                   weights=weights, discriminator=GAIL)  # fmt: skip
    assert f.grad is not None
    torch.testing.assert_close(grad, f.grad)


def test_gail_has_no_supervision_nor_noise_and_its_own_discriminator() -> None:
    gail, airl, hairl = (load_config(algo) for algo in ("gail", "airl", "hairl"))
    assert (gail.alpha, gail.beta, gail.sigma_start, gail.sigma_end) == (0, 0, 0, 0)
    assert (gail.discriminator, airl.discriminator, hairl.discriminator) == ("gail", "airl", "airl")
    # AIRL's and H-AIRL's records keep their keys (and fingerprints); GAIL's name its D
    assert "discriminator" not in airl.to_dict() and "discriminator" not in hairl.to_dict()
    assert gail.to_dict()["discriminator"] == "gail"
    assert load_config("gail", overrides={"discriminator": "gail"}) == gail
    with pytest.raises(ConfigError, match=r"^discriminator 'gail' is not airl's \(airl\); "):
        AIRLConfig.for_algo("airl", discriminator="gail")
    with pytest.raises(ConfigError, match="unknown algo 'sqil'; choose one of airl, hairl, gail"):
        load_config("sqil")


def test_the_commands_offer_the_irl_configs_algorithms() -> None:
    # read from the config (torch-free), never spelled out again
    help_text = CLI.invoke(["gym", "irl", "--help"], terminal_width=100).output
    assert "[airl|hairl|gail]" in help_text and ALGOS == ("airl", "hairl", "gail")


def test_gail_trains_on_the_toy_table_through_pokerirl_train(tmp_path: Path) -> None:
    table = tmp_path / "toy.parquet"
    pq.write_table(toy_expert_table(num_hands=200, seed=5, slip=0.1), table)
    out = tmp_path / "gail"
    args = ["train", str(table), "--out", str(out), "--algo", "gail", "--epochs", "8"]
    result = CLI.invoke([*args, "--batch-size", "64", "--quiet"])
    assert result.exit_code == 0, result.output
    assert result.output.startswith("gail:")
    config = json.loads((out / "config.json").read_text())
    assert config["algo"] == "gail" and config["hyperparameters"]["discriminator"] == "gail"
    assert config["hyperparameters"]["alpha"] == 0 and config["gradients"] == "hand-derived"
    metrics = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    majority = json.loads((out / "baselines.json").read_text())["majority"]
    last = metrics[-1]
    # the policy and the reward's argmax both learn the expert beyond its commonest action
    assert last["val_alignment"] > majority + 0.2 and last["val_reward_alignment"] > majority + 0.2
    assert 0 < last["disc_loss"] < 2 * math.log(2)  # D tells the two apart better than chance


def test_gails_fast_path_follows_autograd_and_differs_from_airl() -> None:
    data = transitions_from_arrow(toy_expert_table(num_hands=150, seed=3))
    train_data, val_data, _ = data.split(val_fraction=0.25, seed=0)
    gail = AIRLConfig.for_algo("gail", epochs=2, batch_size=32)
    runs = [train(train_data, val_data, config=gail, fast_path=f, progress=False)
            for f in (True, False)]  # fmt: skip
    assert [r.gradients for r in runs] == ["hand-derived", "autograd"]
    for a, b in zip(runs[0].reward.parameters(), runs[1].reward.parameters(), strict=True):
        torch.testing.assert_close(a, b, atol=1e-4, rtol=1e-3)
    assert runs[0].metrics[-1]["disc_loss"] == pytest.approx(runs[1].metrics[-1]["disc_loss"],
                                                             abs=1e-3)  # fmt: skip
    airl = train(train_data, val_data, config=AIRLConfig.for_algo("airl", epochs=2, batch_size=32),
                 progress=False)  # fmt: skip
    assert airl.metrics[-1]["disc_loss"] != pytest.approx(runs[0].metrics[-1]["disc_loss"],
                                                          abs=1e-3)  # fmt: skip


@pytest.mark.slow
def test_gail_trains_on_a_tiny_gym_table(tmp_path: Path) -> None:
    from pokerirl.gym.collect import collect
    from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir

    data = tmp_path / "expert.parquet"
    collect(load_expert(resolve_expert_dir("shipped", "MountainCar-v0")), data, transitions=2000,
            seed=0)  # fmt: skip
    out = tmp_path / "irl"
    args = ["gym", "irl", "MountainCar-v0", "--data", str(data), "--algo", "gail", "--runs", "1"]
    args += ["--epochs", "3", "--preset", "quick", "--out", str(out)]
    result = CLI.invoke(args)
    assert result.exit_code == 0, result.output
    assert "MountainCar-v0 gail: final return" in result.output
    run = out / "run-0"
    config = json.loads((run / "config.json").read_text())
    assert config["algo"] == "gail" and config["hyperparameters"]["discriminator"] == "gail"
    metrics = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    majority = json.loads((run / "baselines.json").read_text())["majority"]
    assert metrics[0]["disc_loss"] > metrics[-1]["disc_loss"]  # D learns
    assert metrics[-1]["val_reward_alignment"] > majority + 0.2
