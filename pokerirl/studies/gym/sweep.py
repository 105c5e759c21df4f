"""One-factor-at-a-time ablations of H-AIRL (the paper's Figure 5): :func:`run_sweep`
(``pokerirl sweep``).

Each parameter (α, β, σ_start, σ_end) is varied alone from the preset's H-AIRL settings; each
point runs the IRL phase (``runs`` runs in lock-step) and then the RL phase on each run's
learned reward, over the same expert data. Points that coincide (every parameter at its
preset value) are computed once. ``out`` gets::

    expert.parquet, expert.unit.json     the expert data, shared by every point
    points/<point>/irl/hairl/            the point's IRL runs (a gym irl folder)
    points/<point>/rl/hairl/run-<k>      RL on run k's reward, seed seed + k
    sweep.csv                            one row per (parameter, value): finals, mean and std
    sweep.json                           the same, with the settings and the curves' finals
    <parameter>.png                      the finals against the parameter's values

Every unit is resumable as in the study (:mod:`pokerirl.studies.gym.units`).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.atomic import atomic_path, write_text
from pokerirl.errors import PokerIRLError
from pokerirl.execution import Backend
from pokerirl.gym.irl import GymIRLSummary, irl_config
from pokerirl.gym.presets import TASKS
from pokerirl.gym.rl import DEFAULT_RL_BACKEND
from pokerirl.irl.metrics import Metric
from pokerirl.meanstd import mean_and_std
from pokerirl.serial import Serializable
from pokerirl.studies.common import StudyError, study_folder
from pokerirl.studies.gym.config import StudyPreset
from pokerirl.studies.gym.pipeline import (
    check_rl_backend,
    data_job,
    irl_job,
    rl_curves,
    rl_jobs,
)
from pokerirl.studies.gym.units import DATA_FILE, Say, run_data_jobs, run_irl_jobs, run_rl_jobs

SWEEP_FORMAT = "pokerirl-gym-sweep/1"
PARAMS = ("alpha", "beta", "sigma_start", "sigma_end")
LABELS = {"alpha": "α", "beta": "β", "sigma_start": "σ_start", "sigma_end": "σ_end"}
CSV_FILE, JSON_FILE = "sweep.csv", "sweep.json"
CSV_COLUMNS = (
    "param",
    "value",
    "point",
    "runs",
    "irl_final_return_mean",
    "irl_final_return_std",
    "rl_final_return_mean",
    "rl_final_return_std",
    "final_alignment_mean",
    "final_alignment_std",
    "final_reward_alignment_mean",
    "final_reward_alignment_std",
)


@dataclass(frozen=True, kw_only=True)
class SweepPoint:
    """One point of the sweep: the parameter varied, its value, and every ablated setting."""

    param: str
    value: float
    settings: dict[str, float]  # alpha, beta, sigma_start, sigma_end at this point

    @property
    def name(self) -> str:
        """The point's folder, ``alpha=0.1_beta=0.25_sigma_start=1_sigma_end=0.04``."""
        return "_".join(f"{key}={self.settings[key]:g}" for key in PARAMS)


@dataclass(frozen=True, kw_only=True)
class SweepRow(Serializable):
    """One (parameter, value): its point and the finals over runs (alignment: discrete
    tasks only). The fields are ``sweep.csv``'s columns and ``sweep.json``'s row names."""

    param: str
    value: float
    point: str
    runs: int
    irl_final_return_mean: float
    irl_final_return_std: float
    rl_final_return_mean: float
    rl_final_return_std: float
    final_alignment_mean: float | None = None
    final_alignment_std: float | None = None
    final_reward_alignment_mean: float | None = None
    final_reward_alignment_std: float | None = None


@dataclass(frozen=True, kw_only=True)
class SweepResult:
    """What :func:`run_sweep` wrote: one row per (parameter, value)."""

    out: Path
    env: str
    rows: tuple[SweepRow, ...]
    figures: tuple[Path, ...]


def parse_param(text: str) -> tuple[str, tuple[float, ...]]:
    """``alpha=0,0.1,0.5`` as (name, values).

    >>> parse_param("alpha=0,0.1,0.5")
    ('alpha', (0.0, 0.1, 0.5))
    """
    name, sign, values = text.partition("=")
    name = name.strip()
    if not sign or name not in PARAMS:
        raise StudyError(
            f"bad sweep parameter {text!r}; write NAME=V1,V2,... with NAME one of "
            f"{', '.join(PARAMS)}"
        )
    try:
        parsed = tuple(float(v) for v in values.split(",") if v.strip())
    except ValueError:
        raise StudyError(f"bad sweep parameter {text!r}: the values must be numbers") from None
    if not parsed:
        raise StudyError(f"bad sweep parameter {text!r}: no values")
    if len(set(parsed)) != len(parsed):
        raise StudyError(f"bad sweep parameter {text!r}: a value is repeated")
    bad = [
        v for v in parsed if not math.isfinite(v) or v < 0 or (name in ("alpha", "beta") and v > 1)
    ]
    if bad:
        bounds = "in [0, 1]" if name in ("alpha", "beta") else "at least 0"
        raise StudyError(f"bad sweep parameter {text!r}: {name} must be {bounds}, got {bad[0]:g}")
    return name, parsed


def sweep_points(
    env: str, params: Mapping[str, Sequence[float]], preset: StudyPreset
) -> list[SweepPoint]:
    """One point per (parameter, value), the others at the preset's H-AIRL values."""
    base = preset.irl(env)
    defaults = {key: float(getattr(base, key)) for key in PARAMS}
    return [
        SweepPoint(param=param, value=float(value), settings={**defaults, param: float(value)})
        for param, values in params.items()
        for value in values
    ]


def run_sweep(
    env: str,
    params: Mapping[str, Sequence[float]],
    preset: StudyPreset,
    out: str | os.PathLike[str],
    *,
    backend: Backend | None = None,
    overwrite: bool = False,
    progress: bool = False,
    say: Say = lambda message: None,
    rl_backend: str = DEFAULT_RL_BACKEND,
) -> SweepResult:
    """Run (or resume) the sweep of ``params`` on ``env`` with ``preset``'s budgets; the RL runs
    train with ``rl_backend`` (lockstep: each point's unfinished runs as one group)."""
    from pokerirl.gym.envs import require_gym

    require_gym()
    if env not in TASKS:
        raise StudyError(f"unknown task {env!r}; choose one of {', '.join(TASKS)}")
    check_rl_backend(rl_backend)
    if not params:
        raise StudyError("no parameter to sweep; give one, e.g. alpha=0,0.5,1")
    backend = backend or Backend()
    out = study_folder(out)
    points = sweep_points(env, params, preset)
    unique = list({point.name: point for point in points}.values())
    data = out / DATA_FILE
    options: dict[str, Any] = {"backend": backend, "overwrite": overwrite, "progress": progress}
    irl = {
        p.name: irl_job(out / "points" / p.name, env, "hairl", preset, data=data, **p.settings)
        for p in unique
    }
    for name, job in irl.items():  # every point's settings are checked before anything runs
        try:
            irl_config("hairl", job.settings, seed=preset.seed)
        except ValueError as error:
            raise StudyError(f"point {name}: {error}") from None
    try:
        say(f"[1/4] expert data: {env}")
        run_data_jobs([data_job(out, env, preset)], **options)
        say(f"[2/4] IRL: {len(unique)} H-AIRL points x {preset.runs} runs")
        run_irl_jobs(list(irl.values()), **options)
        rl = [
            job
            for p in unique
            for job in rl_jobs(out / "points" / p.name, env, "hairl", irl[p.name], preset,
                               backend=rl_backend)
        ]
        say(f"[3/4] RL: {len(rl)} runs on the points' rewards")
        run_rl_jobs(rl, **options)
    except PokerIRLError:
        raise  # a unit's conflict keeps its remedy for the command line's advice
    except ValueError as error:
        raise StudyError(str(error)) from None

    say(f"[4/4] {CSV_FILE}, {JSON_FILE} and one figure per parameter -> {out}")
    rows = [point_row(out, point, preset, discrete=TASKS[env].discrete) for point in points]
    write_text(out / CSV_FILE, _csv(rows))
    expert = GymIRLSummary.read(irl[unique[0].name].folder)
    record = {
        "format": SWEEP_FORMAT,
        "env": env,
        "preset": preset.name,
        "runs": preset.runs,
        "seeds": [preset.seed + k for k in range(preset.runs)],
        "base": {key: float(getattr(preset.irl(env), key)) for key in PARAMS},
        "rl_backend": rl_backend,
        "expert_return": expert.expert_return,
        "random_return": expert.over_runs.baselines["random"].mean,
        "rows": [row.to_json() for row in rows],
    }
    write_text(out / JSON_FILE, json.dumps(record, indent=2) + "\n")
    figures = tuple(plot_param(record, param, out / f"{param}.png") for param in params)
    return SweepResult(out=out, env=env, rows=tuple(rows), figures=figures)


def point_row(
    out: Path, point: SweepPoint, preset: StudyPreset, *, discrete: bool
) -> SweepRow:
    """The point's finals: IRL-phase return, RL-phase return, alignment (discrete tasks)."""
    root = out / "points" / point.name
    irl = GymIRLSummary.read(root / "irl" / "hairl")
    rl_mean, rl_std = mean_and_std(rl_curves(root, "hairl", preset.runs).per_run_final)
    alignment: dict[str, float | None] = {}
    for name, metric in (
        ("final_alignment", Metric.VAL_ALIGNMENT),
        ("final_reward_alignment", Metric.VAL_REWARD_ALIGNMENT),
    ):
        curve = metric.of(irl.over_runs.metrics, None) if discrete else None
        alignment[f"{name}_mean"] = None if curve is None else curve.mean[-1]
        alignment[f"{name}_std"] = None if curve is None else curve.std[-1]
    return SweepRow(
        param=point.param,
        value=point.value,
        point=point.name,
        runs=preset.runs,
        irl_final_return_mean=irl.irl_final_return.measured[0],
        irl_final_return_std=irl.irl_final_return.measured[1],
        rl_final_return_mean=rl_mean,
        rl_final_return_std=rl_std,
        **alignment,
    )


def _csv(rows: Sequence[SweepRow]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=CSV_COLUMNS, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        cells = row.to_json()
        writer.writerow({key: "" if cells[key] is None else cells[key] for key in CSV_COLUMNS})
    return buffer.getvalue()


def plot_param(record: Mapping[str, Any], param: str, path: Path) -> Path:
    """The finals against ``param``'s values (mean ± std over runs), the preset's value marked;
    the returns beside the expert's and a random policy's, alignment for discrete tasks."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from pokerirl.figures import finish

    rows = sorted((r for r in record["rows"] if r["param"] == param), key=lambda r: r["value"])
    panels = [("irl_final_return", "IRL-phase return"), ("rl_final_return", "RL-phase return")]
    if rows[0]["final_alignment_mean"] is not None:
        panels.append(("final_alignment", "validation alignment"))
    figure = Figure(figsize=(4.2 * len(panels), 3.8), dpi=100)
    FigureCanvasAgg(figure)
    x = np.array([r["value"] for r in rows])
    for i, (key, title) in enumerate(panels):
        axes = figure.add_subplot(1, len(panels), i + 1)
        mean = np.array([r[f"{key}_mean"] for r in rows], dtype=float)
        std = np.array([r[f"{key}_std"] for r in rows], dtype=float)
        axes.errorbar(x, mean, yerr=std, marker="o", capsize=3, color="C1", label="H-AIRL")
        axes.axvline(record["base"][param], color="grey", linestyle=":", linewidth=1,
                     label=f"preset {record['base'][param]:g}")  # fmt: skip
        if key != "final_alignment":
            for value, label, style in (
                (record["expert_return"], "expert", "--"),
                (record["random_return"], "random", "-."),
            ):
                if math.isfinite(value):
                    axes.axhline(value, color="grey", linestyle=style, linewidth=1, label=label)
        finish(axes, title=title, xlabel=LABELS[param],
               ylabel="return (sum of rewards per episode)" if i < 2
               else "validation alignment (share of states)")  # fmt: skip
    figure.suptitle(
        f"{record['env']}: H-AIRL, {LABELS[param]} varied ({record['preset']} preset); "
        f"points: mean of {record['runs']} runs, bars: ± 1 std (sample) over runs", fontsize=10
    )
    figure.tight_layout()
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format="png", metadata={"Software": None})
    return path
