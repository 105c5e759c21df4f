"""The paper's Gymnasium tasks as typed data: the authors' IRL and RL settings, their final
values, random-policy scores (the study presets are :mod:`pokerirl.studies.gym.config`'s).

The settings are facts from the authors' public code (issue 10's tables); nothing here runs
anything or imports Gymnasium.

>>> TASKS["MountainCar-v0"].rl.algo
'dqn'
>>> TASKS["LunarLander-v3"].irl.policy_hidden
(64, 64)
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import StrEnum
from typing import Any, Literal

from pokerirl.errors import ConfigError
from pokerirl.meanstd import MeanStd

Algo = Literal["ppo", "dqn"]


class RLBackend(StrEnum):
    """How RL runs train: ``sb3`` (one SB3 run per unit) or ``lockstep`` (many in one process,
    :mod:`pokerirl.gym.lockstep`). Here, torch-free, for the reports that name it."""

    SB3 = "sb3"
    LOCKSTEP = "lockstep"


@dataclass(frozen=True, kw_only=True)
class IRLSettings:
    """The authors' IRL-phase settings for one task (both nets share the learning rate)."""

    policy_hidden: tuple[int, ...]
    reward_hidden: tuple[int, ...]
    epochs: int
    learning_rate: float
    transitions: int
    eval_episodes: int
    batch_size: int
    alpha: float
    beta: float
    sigma_start: float
    sigma_end: float
    sigma_decay: float = 0.01
    # The authors use no weight decay on the reward net for any Gymnasium task: 0, as is
    # AIRLConfig.reward_weight_decay's default now. (That default was once 5e-3, the authors'
    # poker value, now the poker study's AUTHORS_IRL only; it leaked in here before issue 20.)
    reward_weight_decay: float = 0.0
    # Options of the IRL core (pokerirl.irl.config, issue 20): H-AIRL's noise ("ours" or
    # "authors") and supervised term ("mean_mse" or the authors' "sum_mse"); the policy's
    # log σ floor in training (-20 never binds).
    noise_form: str = "ours"
    supervised_form: str = "mean_mse"
    log_std_min: float = -20.0
    # Ours, not the paper's (which does not say): train on observations standardized with the
    # training split's mean and std, folded into the saved nets' first layers. False feeds raw
    # observations, which leaves MountainCar's velocity (|v| < 0.07) nearly invisible.
    standardize_obs: bool = True


@dataclass(frozen=True, kw_only=True)
class PPOSettings:
    """SB3 PPO keyword arguments (n_epochs is 20 throughout in the authors' code)."""

    n_steps: int
    batch_size: int
    gamma: float
    gae_lambda: float
    clip_range: float
    ent_coef: float
    vf_coef: float
    max_grad_norm: float
    learning_rate: float
    n_epochs: int = 20
    # Separate pi / vf nets; None keeps SB3's default MlpPolicy (64, 64 tanh, ortho init).
    net_arch: tuple[int, ...] | None = None
    activation: Literal["tanh", "leaky_relu"] = "tanh"
    log_std_init: float = 0.0
    ortho_init: bool = True


@dataclass(frozen=True, kw_only=True)
class DQNSettings:
    """SB3 DQN keyword arguments: rl-zoo's MountainCar-v0 settings."""

    learning_rate: float = 4e-3
    batch_size: int = 128
    buffer_size: int = 10_000
    learning_starts: int = 1_000
    gamma: float = 0.98
    target_update_interval: int = 600
    train_freq: int = 16
    gradient_steps: int = 8
    exploration_fraction: float = 0.2
    exploration_final_eps: float = 0.07
    net_arch: tuple[int, ...] = (256, 256)


@dataclass(frozen=True, kw_only=True)
class RLSettings:
    """The RL phase (and the experts): algorithm, budget and its settings."""

    algo: Algo
    timesteps: int
    ppo: PPOSettings | None = None
    dqn: DQNSettings | None = None

    def __post_init__(self) -> None:
        if (self.algo == "ppo") != (self.ppo is not None) or (self.algo == "dqn") != (
            self.dqn is not None
        ):
            raise ValueError(f"RLSettings: algo {self.algo!r} needs exactly its own settings")

    @property
    def own(self) -> PPOSettings | DQNSettings:
        """The settings of this algorithm (``ppo`` or ``dqn``, whichever it is)."""
        own = self.ppo if self.algo == "ppo" else self.dqn
        assert own is not None  # __post_init__ holds it
        return own


@dataclass(frozen=True, kw_only=True)
class PaperFinals:
    """The authors' final values (for the study's report.md)."""

    irl_airl: MeanStd
    irl_hairl: MeanStd
    irl_expert: MeanStd
    rl_airl: MeanStd
    rl_hairl: MeanStd
    rl_env_reward: MeanStd
    alignment_airl: float | None = None  # %, discrete tasks only
    alignment_hairl: float | None = None


@dataclass(frozen=True, kw_only=True)
class Task:
    """One of the paper's six tasks, or (``paper`` None) any other Gymnasium task with the
    generic settings of :func:`generic_task`."""

    env_id: str
    discrete: bool
    irl: IRLSettings
    rl: RLSettings
    # The authors' expert return (the bar for a shipped expert), a random policy's return
    # (issue 10) and the paper's finals: None for a generic task, which the paper lacks.
    expert_target: float | None
    random_return: float | None
    paper: PaperFinals | None
    version_note: str = ""

    @property
    def generic(self) -> bool:
        """Not one of the paper's tasks: generic settings, no shipped expert, no finals."""
        return self.paper is None


# The authors' PPO policy for LunarLander, Ant and HalfCheetah: separate [256, 256] LeakyReLU
# nets, log_std_init -2, no orthogonal init.
_BIG: dict[str, Any] = dict(
    net_arch=(256, 256), activation="leaky_relu", log_std_init=-2.0, ortho_init=False
)


# Ant-v4 and HalfCheetah-v4 share the authors' IRL settings.
_MUJOCO_IRL = IRLSettings(
    policy_hidden=(64, 64),
    reward_hidden=(64, 64),
    epochs=30,
    learning_rate=2e-4,
    transitions=300_000,
    eval_episodes=10,
    batch_size=64,
    alpha=0.33,
    beta=0.25,
    sigma_start=1.0,
    sigma_end=0.02,
)


def _ms(mean: float, std: float | None = None) -> MeanStd:
    return MeanStd(mean=mean, std=std)


TASKS: dict[str, Task] = {
    task.env_id: task
    for task in (
        Task(
            env_id="Acrobot-v1",
            discrete=True,
            irl=IRLSettings(
                policy_hidden=(64,),
                reward_hidden=(64,),
                epochs=30,
                learning_rate=1e-5,
                transitions=100_000,
                eval_episodes=10,
                batch_size=64,
                alpha=0.10,
                beta=0.00,
                sigma_start=1.0,
                sigma_end=0.04,
            ),
            rl=RLSettings(
                algo="ppo",
                timesteps=100_000,
                ppo=PPOSettings(
                    n_steps=512,
                    batch_size=64,
                    gamma=0.95,
                    gae_lambda=0.95,
                    clip_range=0.1,
                    ent_coef=0.0004,
                    vf_coef=0.5,
                    max_grad_norm=0.8,
                    learning_rate=1e-4,
                ),
            ),
            expert_target=-100.0,
            random_return=-500.0,
            paper=PaperFinals(
                irl_airl=_ms(-81.7, 3.3),
                irl_hairl=_ms(-91.6, 11.1),
                irl_expert=_ms(-94.9),
                rl_airl=_ms(-79.9, 12.8),
                rl_hairl=_ms(-77.9, 8.8),
                rl_env_reward=_ms(-81.0, 6.2),
                alignment_airl=83.0,
                alignment_hairl=83.0,
            ),
        ),
        Task(
            env_id="MountainCar-v0",
            discrete=True,
            irl=IRLSettings(
                policy_hidden=(64,),
                reward_hidden=(64,),
                epochs=40,
                learning_rate=3e-4,
                transitions=100_000,
                eval_episodes=10,
                batch_size=64,
                alpha=0.10,
                beta=0.25,
                sigma_start=1.0,
                sigma_end=0.04,
            ),
            rl=RLSettings(algo="dqn", timesteps=200_000, dqn=DQNSettings()),
            expert_target=-130.0,
            random_return=-200.0,
            paper=PaperFinals(
                irl_airl=_ms(-200.0, 0.0),
                irl_hairl=_ms(-123.3, 8.0),
                irl_expert=_ms(-124.0),
                rl_airl=_ms(-200.0, 0.0),
                rl_hairl=_ms(-127.8, 27.5),
                rl_env_reward=_ms(-149.5, 36.7),
                alignment_airl=43.8,
                alignment_hairl=82.4,
            ),
        ),
        Task(
            env_id="LunarLander-v3",
            discrete=True,
            irl=IRLSettings(
                policy_hidden=(64, 64),
                reward_hidden=(64, 32),
                epochs=50,
                learning_rate=2e-4,
                transitions=300_000,
                eval_episodes=20,
                batch_size=64,
                alpha=0.33,
                beta=0.10,
                sigma_start=1.0,
                sigma_end=0.02,
            ),
            rl=RLSettings(
                algo="ppo",
                timesteps=500_000,
                ppo=PPOSettings(
                    n_steps=960,
                    batch_size=64,
                    gamma=0.999,
                    gae_lambda=0.95,
                    clip_range=0.2,
                    ent_coef=0.01,
                    vf_coef=0.5,
                    max_grad_norm=0.6,
                    learning_rate=3e-4,
                    **_BIG,
                ),
            ),
            expert_target=160.0,
            random_return=-240.0,
            paper=PaperFinals(
                irl_airl=_ms(-680.9, 209.0),
                irl_hairl=_ms(173.2, 21.5),
                irl_expert=_ms(172.6),
                rl_airl=_ms(-85.5, 139.0),
                rl_hairl=_ms(1.2, 159.0),
                rl_env_reward=_ms(227.5, 91.0),
                alignment_airl=56.4,
                alignment_hairl=75.2,
            ),
            version_note=(
                "The paper used LunarLander-v2, which Gymnasium 1.x removed; v3 fixes bugs and "
                "widens the observation bounds. Returns are on the same scale."
            ),
        ),
        Task(
            env_id="Pendulum-v1",
            discrete=False,
            irl=IRLSettings(
                policy_hidden=(64, 64),
                reward_hidden=(64, 64),
                epochs=30,
                learning_rate=2e-4,
                transitions=300_000,
                eval_episodes=10,
                batch_size=64,
                alpha=0.33,
                beta=0.25,
                sigma_start=1.0,
                sigma_end=0.03,
            ),
            rl=RLSettings(
                algo="ppo",
                timesteps=150_000,
                ppo=PPOSettings(
                    n_steps=256,
                    batch_size=64,
                    gamma=0.95,
                    gae_lambda=0.95,
                    clip_range=0.1,
                    ent_coef=0.0004,
                    vf_coef=0.5,
                    max_grad_norm=0.8,
                    learning_rate=5e-4,
                ),
            ),
            expert_target=-200.0,
            random_return=-1200.0,
            paper=PaperFinals(
                irl_airl=_ms(-237.0, 120.0),
                irl_hairl=_ms(-167.7, 26.5),
                irl_expert=_ms(-158.2),
                rl_airl=_ms(-575.0, 462.0),
                rl_hairl=_ms(-821.0, 562.0),
                rl_env_reward=_ms(-304.0, 377.0),
            ),
        ),
        Task(
            env_id="Ant-v4",
            discrete=False,
            irl=_MUJOCO_IRL,
            rl=RLSettings(
                algo="ppo",
                timesteps=600_000,
                ppo=PPOSettings(
                    n_steps=896,
                    batch_size=128,
                    gamma=0.98,
                    gae_lambda=0.92,
                    clip_range=0.1,
                    ent_coef=0.0004,
                    vf_coef=0.58,
                    max_grad_norm=0.8,
                    learning_rate=4e-5,
                    **_BIG,
                ),
            ),
            expert_target=1400.0,
            random_return=-16.0,
            paper=PaperFinals(
                irl_airl=_ms(1317.0, 162.0),
                irl_hairl=_ms(1486.0, 207.0),
                irl_expert=_ms(1461.0),
                rl_airl=_ms(982.0, 19.0),
                rl_hairl=_ms(2598.0, 602.0),
                rl_env_reward=_ms(1573.0, 550.0),
            ),
            version_note=(
                "Kept at v4 as in the paper: Ant-v5 has 105-dimensional observations and another "
                "reward. Standing still scores about +1,000 (the healthy bonus)."
            ),
        ),
        Task(
            env_id="HalfCheetah-v4",
            discrete=False,
            irl=_MUJOCO_IRL,
            rl=RLSettings(
                algo="ppo",
                timesteps=1_000_000,
                ppo=PPOSettings(
                    n_steps=960,
                    batch_size=64,
                    gamma=0.98,
                    gae_lambda=0.92,
                    clip_range=0.1,
                    ent_coef=0.000402,
                    vf_coef=0.581,
                    max_grad_norm=0.8,
                    learning_rate=1.6e-5,
                    **_BIG,
                ),
            ),
            expert_target=2900.0,
            random_return=-234.0,
            paper=PaperFinals(
                irl_airl=_ms(2501.0, 189.0),
                irl_hairl=_ms(2753.0, 55.0),
                irl_expert=_ms(2966.0),
                rl_airl=_ms(339.0, 340.0),
                rl_hairl=_ms(2577.0, 697.0),
                rl_env_reward=_ms(2545.0, 1046.0),
            ),
            version_note="Kept at v4 as in the paper (v5 changes the model and defaults).",
        ),
    )
}

# Any other registered Gymnasium task gets these (issue 34): the settings of the paper's tasks of
# its kind, on modest budgets, and SB3's default PPO, which is tuned for no task in particular.
# Discrete: MountainCar's IRL settings (Acrobot's learning rate, 1e-5, is its own). Continuous:
# Pendulum's. 50,000 expert transitions and 100,000 RL steps keep a first run short; a task
# that needs more takes the command line's overrides.
GENERIC_PPO = PPOSettings(
    n_steps=2048,
    batch_size=64,
    gamma=0.99,
    gae_lambda=0.95,
    clip_range=0.2,
    ent_coef=0.0,
    vf_coef=0.5,
    max_grad_norm=0.5,
    learning_rate=3e-4,
    n_epochs=10,
)
GENERIC_TRANSITIONS = 50_000
GENERIC_RL_TIMESTEPS = 100_000


def generic_task(env_id: str, *, discrete: bool) -> Task:
    """The settings for a task the paper does not have, from its action space's kind.

    >>> task = generic_task("CartPole-v1", discrete=True)
    >>> task.generic, task.irl.policy_hidden, task.rl.algo, task.irl.transitions
    (True, (64,), 'ppo', 50000)
    """
    if env_id in TASKS:
        raise ConfigError(f"{env_id} is one of the paper's tasks: use TASKS[{env_id!r}]")
    like = TASKS["MountainCar-v0" if discrete else "Pendulum-v1"].irl
    return Task(
        env_id=env_id,
        discrete=discrete,
        irl=replace(like, transitions=GENERIC_TRANSITIONS),
        rl=RLSettings(algo="ppo", timesteps=GENERIC_RL_TIMESTEPS, ppo=GENERIC_PPO),
        expert_target=None,
        random_return=None,
        paper=None,
    )


# Cheapest first: the order experts are trained in and the study runs tasks in.
# The most expert rows one table may hold: a table is held in memory until it is written
# (10 million rows of Ant-v4 are about 2.4 GB); the paper uses at most 300,000.
MAX_TRANSITIONS = 10_000_000

TASK_ORDER: tuple[str, ...] = (
    "Acrobot-v1",
    "MountainCar-v0",
    "Pendulum-v1",
    "LunarLander-v3",
    "HalfCheetah-v4",
    "Ant-v4",
)
