"""Tournaments with saved agent folders and agent sets (``seed-<k>`` subfolders)."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from pokerirl.agents import checkpoint, dqn
from pokerirl.tournaments import TournamentError, run_tournament

HANDS = 2_000


def _save(folder: Path, weights_seed: int) -> None:
    torch.manual_seed(weights_seed)
    checkpoint.save_agent(folder, dqn.QNetwork(hidden=(8,)), {"hidden": [8]})


@pytest.fixture()
def agent_sets(tmp_path: Path) -> Path:
    for k in range(3):
        _save(tmp_path / "dqn" / f"seed-{k}", k)
        _save(tmp_path / "hairl-dqn" / f"seed-{k}", 100 + k)
    _save(tmp_path / "single", 7)
    return tmp_path


def test_seed_k_plays_each_sets_seed_k_agent(agent_sets: Path) -> None:
    sets = str(agent_sets / "hairl-dqn"), str(agent_sets / "dqn")
    single = str(agent_sets / "single")
    report = run_tournament(
        [sets, (single, sets[1])], hands=HANDS, seeds=[0, 1, 2], out=agent_sets / "r"
    )
    pair, against_single = report.matchups
    assert (pair.agent_a, pair.agent_b, against_single.agent_a) == ("hairl-dqn", "dqn", "single")
    for k, line in enumerate(pair.seeds):
        assert line.fingerprint_a == checkpoint.folder_fingerprint(Path(sets[0]) / f"seed-{k}")
        assert line.fingerprint_b == checkpoint.folder_fingerprint(Path(sets[1]) / f"seed-{k}")
    assert len({s.fingerprint_b for s in pair.seeds}) == 3
    assert {s.fingerprint_a for s in against_single.seeds} == {
        checkpoint.folder_fingerprint(single)
    }
    assert len({s.mbb_per_hand for s in pair.seeds}) == 3


def test_a_greedy_network_against_itself_is_exactly_even(agent_sets: Path) -> None:
    same = str(agent_sets / "dqn")
    report = run_tournament([(same, same)], hands=HANDS, seeds=[0, 1], out=agent_sets / "r")
    assert [s.mbb_per_hand for s in report.matchups[0].seeds] == [0.0, 0.0]


@pytest.mark.slow
def test_processes_do_not_change_network_results(agent_sets: Path) -> None:
    matchup = [(str(agent_sets / "hairl-dqn"), str(agent_sets / "dqn"))]
    one = run_tournament(matchup, hands=HANDS, seeds=[0, 1], out=agent_sets / "1", jobs=1)
    two = run_tournament(matchup, hands=HANDS, seeds=[0, 1], out=agent_sets / "2", jobs=2)
    assert [(s.mbb_per_hand, s.std_error) for s in one.matchups[0].seeds] == [
        (s.mbb_per_hand, s.std_error) for s in two.matchups[0].seeds
    ]


def test_retrained_agent_is_not_mixed_with_saved_results(agent_sets: Path) -> None:
    matchup = [(str(agent_sets / "hairl-dqn"), "call")]
    run_tournament(matchup, hands=HANDS, seeds=[0, 1], out=agent_sets / "r")
    _save(agent_sets / "hairl-dqn" / "seed-1", 999)  # seed 1 retrained: new weights
    with pytest.raises(TournamentError, match=r"seed-1\.json .*fingerprint_a 'sha256:"):
        run_tournament(matchup, hands=HANDS, seeds=[0, 1], out=agent_sets / "r")
    redone = run_tournament(
        matchup, hands=HANDS, seeds=[0, 1], out=agent_sets / "r", overwrite=True
    )
    assert redone.timing["seeds_reused"] == 1


def test_broken_agent_folder_is_a_one_line_error(agent_sets: Path) -> None:
    (agent_sets / "dqn" / "seed-2" / "model.pt").write_bytes(b"not a checkpoint")
    with pytest.raises(TournamentError, match=r"seed-2[/\\]model\.pt: cannot load agent") as error:
        run_tournament(
            [(str(agent_sets / "dqn"), "call")], hands=HANDS, seeds=[2], out=agent_sets / "r"
        )
    assert "\n" not in str(error.value)


@pytest.mark.filterwarnings("ignore::pokerirl.agents.rlcard_import.UntrustedCheckpointWarning")
def test_rlcard_checkpoint_is_one_agent_for_every_seed(tmp_path: Path) -> None:
    from rlcard.agents import DQNAgent  # imported here: it runs `pip freeze` (seconds)

    from pokerirl.agents import resolve_agent

    DQNAgent(
        num_actions=4, state_shape=[72], mlp_layers=[16], device=torch.device("cpu")
    ).save_checkpoint(str(tmp_path))
    spec = f"rlcard:{tmp_path / 'checkpoint_dqn.pt'}"
    report = run_tournament(
        [(spec, "call"), (spec, spec)], hands=HANDS, seeds=[0, 1], out=tmp_path / "r"
    )
    against_call, mirror = report.matchups
    assert against_call.agent_a == "checkpoint_dqn.pt"
    assert {s.fingerprint_a for s in against_call.seeds} == {resolve_agent(spec).fingerprint}
    assert [s.mbb_per_hand for s in mirror.seeds] == [0.0, 0.0]
    with pytest.raises(TournamentError, match="no such RLCard checkpoint"):
        run_tournament([("rlcard:/no/such.pt", "call")], hands=HANDS, seeds=[0], out=tmp_path)
