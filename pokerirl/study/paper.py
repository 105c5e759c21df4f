"""The paper's poker numbers, in one place (Hybrid-AIRL, Table 1 and the poker figures).

Values the paper gives only approximately (read off its figures) say so in ``APPROXIMATE``.
"""

from __future__ import annotations

from typing import Any

TABLE1: dict[str, dict[str, float]] = {
    "hairl_dqn_vs_dqn": {"mbb_per_hand": 96, "std_error": 14},
    "airl_dqn_vs_dqn": {"mbb_per_hand": -693, "std_error": 34},
}
TABLE1_P_BELOW = 1e-10  # the paper: both Table 1 results at p < 1e-10
IRL_ALIGNMENT: dict[str, dict[str, float]] = {  # validation alignment, mean and std over runs
    "airl": {"mean": 0.531, "std": 0.005},
    "hairl": {"mean": 0.586, "std": 0.002},
}
RL_VS_RANDOM: dict[str, float] = {"dqn": 2270, "airl_dqn": 1817, "hairl_dqn": 2217}  # mbb/h
DISC_ACC_FINAL: dict[str, float] = {"airl": 0.52, "hairl": 0.95}  # end of IRL, about
DQN_TRAINING = "5,000 episodes against random"
APPROXIMATE = ("rl_vs_random", "disc_acc_final")


def paper_values() -> dict[str, Any]:
    """Everything above as one JSON-ready dict (``report.json["paper"]``)."""
    return {
        "table1": TABLE1,
        "table1_p_below": TABLE1_P_BELOW,
        "irl_alignment": IRL_ALIGNMENT,
        "rl_vs_random": RL_VS_RANDOM,
        "disc_acc_final": DISC_ACC_FINAL,
        "dqn_training": DQN_TRAINING,
        "approximate": list(APPROXIMATE),
    }
