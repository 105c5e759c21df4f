"""Hyperparameters of a run (:class:`AIRLConfig`), checked field by field, and TOML loading.
Torch-free (the command line builds its options from these fields without loading torch).

The TOML file is flat, with the field names as keys::

    epochs = 20
    reward_hidden = [64, 64]
    policy_hidden = [64, 64]
    activation = "tanh"
    layer_norm = true
    reward_family = "shaped"
    gamma = 0.99

>>> AIRLConfig.for_algo("airl").alpha, AIRLConfig.for_algo("hairl").alpha
(0.0, 0.33)
>>> AIRLConfig.for_algo("gail").discriminator
<DiscriminatorForm.GAIL: 'gail'>
>>> AIRLConfig(epochs=True)
Traceback (most recent call last):
...
pokerirl.errors.ConfigError: epochs must be an integer, got True
"""

from __future__ import annotations

import dataclasses
import math
import os
import tomllib
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

from pokerirl.errors import ConfigError as ConfigError  # its old home: imports keep working
from pokerirl.settings import (
    MAX_BATCH,
    MAX_LAYERS,
    MAX_WIDTH,
    bounded,
    check_bounds,
    enum_value,
    setting,
    with_overrides,
)


class Activation(StrEnum):
    """The hidden layers' activation (:data:`pokerirl.irl.nets.ACTIVATIONS`)."""

    RELU = "relu"
    TANH = "tanh"
    LEAKY_RELU = "leaky_relu"


class RewardFamily(StrEnum):
    """What the reward net reads: f(s, a), or the shaped g(s, a) + γ h(s') - h(s)."""

    STATE_ACTION = "state_action"
    SHAPED = "shaped"


class Algo(StrEnum):
    """The reward learners: AIRL, H-AIRL (AIRL with supervision and noise), and GAIL (the
    same loop with GAIL's discriminator)."""

    AIRL = "airl"
    HAIRL = "hairl"
    GAIL = "gail"


class IRLMode(StrEnum):
    """Where the policy's actions come from: ``offline`` at the expert's own states
    (:mod:`pokerirl.irl.trainer`), ``online`` from a generator acting in its environment
    (:mod:`pokerirl.irl.online`)."""

    OFFLINE = "offline"
    ONLINE = "online"


class DiscriminatorForm(StrEnum):
    """How D is made from f and π (:mod:`pokerirl.irl.discriminators`): AIRL's
    exp f / (exp f + π), or GAIL's σ(f)."""

    AIRL = "airl"
    GAIL = "gail"


class NoiseSchedule(StrEnum):
    """How σ decays along a batch: ``linear`` (the paper) or ``authors`` (their code)."""

    LINEAR = "linear"
    AUTHORS = "authors"


class DiscAction(StrEnum):
    """What the discriminator sees of π."""

    SAMPLE = "sample"
    DISTRIBUTION = "distribution"


class NoiseForm(StrEnum):
    """Continuous actions only (issue 20). ``ours``: σ in box widths (high - low), the noised
    action clipped to the box, log π at the noised action. ``authors`` (silue-dev/hairl
    src/hairl.py): σ in units of ``high``, no clipping, log π of the clean sample."""

    OURS = "ours"
    AUTHORS = "authors"


class SupervisedForm(StrEnum):
    """The supervised term. ``mean_mse`` (ours): continuous, the batch mean of ‖μ − a_E‖²;
    discrete, the cross-entropy of π at a_E. ``sum_mse`` (the authors'): mse_loss(x, a_E,
    reduction="sum"), summed over the batch, where x is the reparameterized sample
    (continuous: it also penalizes σ²) or π's probabilities against the one-hot a_E
    (discrete)."""

    MEAN_MSE = "mean_mse"
    SUM_MSE = "sum_mse"


MAX_EPOCHS = 1_000_000  # an epoch is a pass over the data: more is a typo
MAX_SEED = 2**32 - 1  # numpy's seeds; the command line offers the same range

# The names, for messages (a StrEnum member is its value: "airl" in ALGOS).
ALGOS: tuple[str, ...] = tuple(Algo)


@dataclass(frozen=True, kw_only=True)
class AIRLConfig:
    """Hyperparameters. The defaults are the H-AIRL paper's reference poker settings."""

    # the nets (see pokerirl.irl.nets.NetSpec)
    reward_hidden: tuple[int, ...] = bounded((64,), min=1, max=MAX_WIDTH, max_len=MAX_LAYERS)
    policy_hidden: tuple[int, ...] = bounded((64,), min=1, max=MAX_WIDTH, max_len=MAX_LAYERS)
    activation: Activation = Activation.RELU
    layer_norm: bool = False
    reward_family: RewardFamily = RewardFamily.STATE_ACTION
    gamma: float = 0.99
    # optimization
    reward_lr: float = setting(1e-3, help="Adam lr of f.")
    policy_lr: float = setting(1e-3, help="Adam lr of the policy.")
    # 0, not the authors' 5e-3: on poker tables their decay flattens f into one value per
    # action, whose legal argmax is "check, else call" (issue 31; their preset keeps it).
    reward_weight_decay: float = setting(0.0, help="Weight decay of f (default 0; authors 5e-3).")
    batch_size: int = setting(256, help="Minibatch size.", min=1, max=MAX_BATCH)
    epochs: int = setting(50, help="Training epochs.", min=1, max=MAX_EPOCHS, show_default=True)
    # the discriminator's form; set by the algorithm (GAIL's for gail), never on its own
    discriminator: DiscriminatorForm = DiscriminatorForm.AIRL
    # H-AIRL
    alpha: float = setting(0.33, help="Supervised weight in policy loss.")
    beta: float = setting(0.0, help="Env-reward weight in disc. loss.")  # on (f - r_env)²
    # noise σ on the first and the last sample of a batch (in action ranges)
    sigma_start: float = setting(1.0, help="Noise std on the batch's first policy action (H-AIRL).")
    sigma_end: float = setting(0.1, help="Noise std on the batch's last policy action (H-AIRL).")
    noise_schedule: NoiseSchedule = NoiseSchedule.LINEAR
    noise_decay: float = 0.1  # k of the authors' schedule: 0.1 poker, 0.01 Gymnasium
    disc_action: DiscAction = DiscAction.SAMPLE
    noise_form: NoiseForm = NoiseForm.OURS
    supervised_form: SupervisedForm = SupervisedForm.MEAN_MSE
    # Continuous policies' log σ is clamped to [log_std_min, log_std_max] in training (the
    # defaults never bind in practice; -5 keeps -log π from winning D alone, issue 20).
    log_std_min: float = -20.0
    log_std_max: float = 2.0
    # data
    val_fraction: float = setting(0.1, help="Share of hands.")  # of groups: hands, episodes
    seed: int = setting(0, help="Seed for init, split, shuffle, noise.", min=0, max=MAX_SEED)

    def __post_init__(self) -> None:
        for item in dataclasses.fields(self):
            value = _checked(item.name, _HINTS[item.name], getattr(self, item.name))
            object.__setattr__(self, item.name, value)
        check_bounds(self)  # before any net is built: a width of 10^9 is refused here
        checks = {
            "batch_size >= 1": self.batch_size >= 1,
            "epochs >= 1": self.epochs >= 1,
            "0 <= alpha <= 1": 0 <= self.alpha <= 1,
            "0 <= beta <= 1": 0 <= self.beta <= 1,
            "sigma_start >= sigma_end >= 0": self.sigma_start >= self.sigma_end >= 0,
            "sigma_end > 0 for the authors' schedule": self.noise_schedule != NoiseSchedule.AUTHORS
            or self.sigma_end > 0
            or self.sigma_start == 0,
            "noise_decay > 0": self.noise_decay > 0,
            "0 < val_fraction < 1": 0 < self.val_fraction < 1,
            "0 <= gamma <= 1": 0 <= self.gamma <= 1,
            "learning rates > 0": self.reward_lr > 0 and self.policy_lr > 0,
            "reward_weight_decay >= 0": self.reward_weight_decay >= 0,
            "hidden widths >= 1": all(w >= 1 for w in self.reward_hidden + self.policy_hidden),
            "a reward hidden layer": len(self.reward_hidden) >= 1,
            "log_std_min < log_std_max": self.log_std_min < self.log_std_max,
        }
        broken = [name for name, ok in checks.items() if not ok]
        if broken:
            raise ConfigError(f"invalid AIRL config: need {'; '.join(broken)}")

    @classmethod
    def for_algo(cls, algo: str, **overrides: Any) -> AIRLConfig:
        """Defaults for ``"airl"`` and ``"gail"`` (α = β = 0, no noise; GAIL's discriminator
        for gail) or ``"hairl"`` (:data:`ALGO_PRESETS`), then ``overrides`` (None: not given).

        Unknown keys raise ``ConfigError`` naming them, and so does a ``discriminator`` that
        is not the algorithm's (the run records the algorithm; its D must be that one's).
        """
        form = DiscriminatorForm.GAIL if algo == Algo.GAIL else DiscriminatorForm.AIRL
        if overrides.get("discriminator", form) not in (form, None):
            raise ConfigError(
                f"discriminator {overrides['discriminator']!r} is not {algo}'s ({form}); "
                "the algorithm sets it: leave it out"
            )
        return with_overrides(ALGO_PRESETS, algo, what="algo", **overrides)

    def to_dict(self) -> dict[str, object]:
        """The settings as JSON, without the continuous-action options (issue 20) that hold
        their defaults: run records and fingerprints written before them stay valid."""
        return {
            k: list(v) if isinstance(v, tuple) else v
            for k, v in vars(self).items()
            if not (k in _ADDED_LATER and v == _ADDED_LATER[k])
        }


# Fields added after runs were recorded, with the defaults that reproduce those runs.
_ADDED_LATER: dict[str, object] = {
    "noise_form": NoiseForm.OURS,
    "supervised_form": SupervisedForm.MEAN_MSE,
    "log_std_min": -20.0,
    "log_std_max": 2.0,
    "discriminator": DiscriminatorForm.AIRL,
}


_HINTS: dict[str, object] = typing.get_type_hints(AIRLConfig)


def _checked(name: str, hint: Any, value: Any) -> Any:
    """``value`` if it has the field's type (ints for floats too, never bools for numbers)."""
    if hint is bool:
        if isinstance(value, bool):
            return value
        raise ConfigError(f"{name} must be true or false, got {value!r}")
    if hint is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        raise ConfigError(f"{name} must be an integer, got {value!r}")
    if hint is float:
        if isinstance(value, int | float) and not isinstance(value, bool):
            if math.isfinite(value):  # an inf learning rate trains NaN nets without a word
                return float(value)
            raise ConfigError(f"{name} must be a finite number, got {value!r}")
        raise ConfigError(f"{name} must be a number, got {value!r}")
    if hint is str:
        if isinstance(value, str):
            return value
        raise ConfigError(f"{name} must be a string, got {value!r}")
    if isinstance(hint, type) and issubclass(hint, StrEnum):
        return enum_value(name, hint, value)
    # tuple[int, ...]: hidden widths
    if isinstance(value, list | tuple) and all(
        isinstance(w, int) and not isinstance(w, bool) for w in value
    ):
        return tuple(value)
    raise ConfigError(f"{name} must be a list of integers, got {value!r}")


_NO_NOISE: dict[str, Any] = {"alpha": 0.0, "beta": 0.0, "sigma_start": 0.0, "sigma_end": 0.0}
# Each algorithm's defaults (AIRLConfig.for_algo).
ALGO_PRESETS: dict[str, AIRLConfig] = {
    Algo.AIRL: AIRLConfig(**_NO_NOISE),
    Algo.HAIRL: AIRLConfig(),
    Algo.GAIL: AIRLConfig(**_NO_NOISE, discriminator=DiscriminatorForm.GAIL),
}


def load_config(
    algo: str,
    *,
    config_file: str | os.PathLike[str] | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> AIRLConfig:
    """The algorithm's defaults, then a TOML file's settings, then ``overrides`` (CLI flags).

    Overrides that are None are ignored. Every problem is a ``ConfigError`` of one line,
    naming the file when the file is at fault.
    """
    settings: dict[str, Any] = {}
    path: Path | None = None
    if config_file is not None:
        path = Path(config_file)
        if not path.is_file():
            raise ConfigError(f"config file not found: {path}")
        try:
            settings = tomllib.loads(path.read_text(encoding="utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
            raise ConfigError(f"cannot parse {path} as TOML: {error}") from None
        if "algo" in settings:
            raise ConfigError(
                f"{path}: 'algo' cannot be set in a config file; the algorithm is chosen on its own"
            )
        try:
            AIRLConfig.for_algo(algo, **settings)  # blame the file for the file's mistakes
        except ConfigError as error:
            raise ConfigError(f"{path}: {error}") from None
    settings.update({k: v for k, v in (overrides or {}).items() if v is not None})
    return AIRLConfig.for_algo(algo, **settings)
