"""Training runs on disk: ``pokerirl train``'s folders, several runs, and ``load_reward``.

A run folder holds ``reward.pt`` and ``policy.pt`` (state_dicts), ``config.json``
(architecture, hyperparameters, data fingerprint, package versions, final metrics: what
determines the result, never wall-clock times), ``timings.json`` (samples/s, seconds),
``metrics.jsonl`` (one line per epoch), ``baselines.json``, ``split.json`` (the validation
group ids), PNG curves and, for a poker table with cards, the reward card
(``reward_card.json`` and ``reward_card.png``: what f prefers on the validation hands; see
:mod:`pokerirl.agents.reward_card`). A folder of several runs holds ``run-<k>`` folders,
each with seed ``seed + k``, and ``summary.json`` (mean and std over runs) with a banded plot.

A finished folder is never modified in place: a run is written into a hidden temporary folder
beside it and renamed into place at the end (replacing an old run only with ``overwrite``).

>>> import tempfile, pyarrow.parquet as pq
>>> from pokerirl.irl.toy import toy_expert_table
>>> from pokerirl.irl.config import load_config
>>> tmp = Path(tempfile.mkdtemp())
>>> pq.write_table(toy_expert_table(num_hands=200), tmp / "table.parquet")
>>> config = load_config("hairl", overrides={"epochs": 2, "batch_size": 64})
>>> summary = train_table(tmp / "table.parquet", tmp / "run", config=config, progress=False)
>>> sorted(summary.baselines)
['bc', 'legal_majority', 'majority']
>>> reward = load_reward(tmp / "run")
>>> reward(np.zeros((3, 72), np.uint8), np.array([0, 1, 3])).dtype
dtype('float32')
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import uuid
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from pokerirl.atomic import make_shareable, write_text, write_torch
from pokerirl.execution import (
    Backend,
    UnitConflict,
    bytes_fingerprint,
    load_unit_folder,
    map_units,
    save_unit_folder,
)
from pokerirl.irl.airl import (
    TrainResult,
    baselines,
    default_nets,
    resolve_device,
    train,
)
from pokerirl.irl.config import AIRLConfig
from pokerirl.irl.nets import ACTIVATIONS, REWARD_FAMILIES, NetSpec, build_nets
from pokerirl.irl.plots import plot_bands, plot_curves
from pokerirl.irl.table import first_line, read_table
from pokerirl.irl.transitions import Transitions
from pokerirl.versions import package_versions

FORMAT_VERSION = 2
REWARD_FILE, POLICY_FILE, CONFIG_FILE = "reward.pt", "policy.pt", "config.json"
METRICS_FILE, BASELINES_FILE, SPLIT_FILE = "metrics.jsonl", "baselines.json", "split.json"
TIMINGS_FILE, SUMMARY_FILE = "timings.json", "summary.json"


class RunError(ValueError):
    """A run folder, or a file in it, that cannot be used: one line naming it."""


@dataclass(frozen=True)
class RunSummary:
    """What :func:`train_table` did (or, for several runs, the first run and all of them)."""

    out_dir: Path
    metrics: list[dict[str, Any]]
    baselines: dict[str, float]
    samples_per_second: float
    train_rows: int
    val_rows: int
    runs: tuple[dict[str, Any], ...] = ()  # several runs: each run's unit result


# --------------------------------------------------------------------------- one run


def train_table(
    table: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    algo: str = "hairl",
    config: AIRLConfig | None = None,
    device: str = "cpu",
    progress: bool = True,
    overwrite: bool = False,
) -> RunSummary:
    """Train on a Parquet decision table and write the run folder ``out_dir``.

    Validation is a seeded share of the *hands* (``config.val_fraction``), never of rows.
    """
    config = config or AIRLConfig.for_algo(algo)
    resolve_device(device)  # fail before reading a large table
    out = Path(out_dir)
    check_destination(out, overwrite=overwrite)
    data = read_table(table)
    with staged_folder(out, overwrite=overwrite) as folder:
        summary = train_into(
            data, folder, algo=algo, config=config, device=device, progress=progress, table=table
        )
    return replace(summary, out_dir=out)


def train_into(
    data: Transitions,
    folder: Path,
    *,
    algo: str,
    config: AIRLConfig,
    device: str = "cpu",
    progress: bool = False,
    table: str | os.PathLike[str] | None = None,
    table_file: str | os.PathLike[str] | None = None,
) -> RunSummary:
    """Split, compute the baselines, train and write a run into the (new) ``folder``.

    ``table`` is the table's path for the record; ``table_file`` the file to read the reward
    card's states from (default ``table``)."""
    train_data, val_data, val_groups = data.split(
        val_fraction=config.val_fraction, seed=config.seed
    )
    folder.mkdir(parents=True, exist_ok=True)
    write_text(folder / SPLIT_FILE, json.dumps({"validation_groups": val_groups}) + "\n")
    found = run_baselines(train_data, val_data, config=config, device=device, progress=progress)
    write_text(folder / BASELINES_FILE, json.dumps(found, indent=2) + "\n")

    lines: list[str] = []

    def log_epoch(metrics: dict[str, Any]) -> None:
        # Rewrite the whole (small) file each epoch: readable live, never half-written.
        lines.append(json.dumps(metrics))
        write_text(folder / METRICS_FILE, "\n".join(lines) + "\n")

    result = train(
        train_data,
        val_data,
        config=config,
        device=device,
        progress=progress,
        on_epoch=log_epoch,
    )
    data_info = data_record(data, train_data, val_data, path=table)
    save_run(result, folder, algo=algo, data=data_info, baselines=found, device=device)
    plot_curves(result.metrics, folder, baselines=found)
    write_reward_card(folder, table_file or table)
    return RunSummary(
        out_dir=folder,
        metrics=result.metrics,
        baselines=found,
        samples_per_second=result.samples_per_second,
        train_rows=len(train_data),
        val_rows=len(val_data),
    )


CARD_COLUMNS = ("hole_cards", "board")  # what the card reads beyond the trainer's columns


def write_reward_card(folder: Path, table: str | os.PathLike[str] | None) -> None:
    """The run's reward card over its validation hands, when ``table`` has the cards.

    The one call of the train fan-out into the agents layer (the card is poker-specific);
    it moves with the fan-out when that leaves ``irl/``.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    if table is None:
        return
    try:
        names = pq.read_schema(table).names
    except (OSError, pa.ArrowException):
        return
    if all(name in names for name in CARD_COLUMNS):
        from pokerirl.agents.reward_card import run_card, write_card

        write_card(run_card(folder, table), folder)


def data_record(
    data: Transitions,
    train_data: Transitions,
    val_data: Transitions,
    *,
    path: str | os.PathLike[str] | None,
) -> dict[str, Any]:
    """What a run's ``config.json`` says of its data: where, which bytes, how it was split."""
    return {
        "path": None if path is None else str(Path(path).resolve()),
        "sha256": data.fingerprint(),
        "rows": len(data),
        "groups": len(np.unique(data.groups)),
        "train_rows": len(train_data),
        "val_rows": len(val_data),
        "has_reward": data.rewards is not None,
        "has_next_obs": data.next_obs is not None,
    }


def run_baselines(
    train_data: Transitions,
    val_data: Transitions,
    *,
    config: AIRLConfig,
    device: str = "cpu",
    progress: bool = False,
) -> dict[str, float]:
    """``majority`` and ``legal_majority`` (discrete), and ``bc``: the same policy net, same
    initialization and epochs, trained with α = 1 and no adversary, on the same split.

    ``bc`` is its final validation alignment (discrete) or validation MSE (continuous).
    The dict is plain: callers (the Gymnasium layer) add keys such as ``random``, ``expert``.
    """
    found = baselines(train_data, val_data) if train_data.discrete else {}
    reward, policy = default_nets(train_data, config)
    bc = train(
        train_data,
        val_data,
        config=replace(config, alpha=1.0),
        reward=reward,
        policy=policy,
        adversarial=False,
        device=device,
        progress=progress,
    )
    last = bc.metrics[-1]
    found["bc"] = last["val_alignment"] if train_data.discrete else last["val_mse"]
    return found


def save_run(
    result: TrainResult,
    out_dir: str | os.PathLike[str],
    *,
    algo: str,
    data: Mapping[str, Any],
    baselines: Mapping[str, float] | None = None,
    device: str = "cpu",
) -> None:
    """Write ``reward.pt``, ``policy.pt``, ``config.json`` and ``timings.json``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for module, name in ((result.reward, REWARD_FILE), (result.policy, POLICY_FILE)):
        # Clone: training keeps parameters as views of one flat buffer; save each on its own.
        state = {k: v.detach().cpu().clone() for k, v in module.state_dict().items()}
        write_torch(out / name, state)
    policy = result.policy
    if isinstance(getattr(policy, "low", None), Tensor):
        space: dict[str, Any] = {
            "type": "box",
            "low": policy.low.tolist(),  # type: ignore[union-attr]
            "high": policy.high.tolist(),  # type: ignore[union-attr]
        }
    else:
        space = {"type": "discrete", "num_actions": int(policy.action_dim)}  # type: ignore[arg-type]
    config = result.config
    record = {
        "format_version": FORMAT_VERSION,
        "algo": algo,
        "architecture": {
            "obs_dim": int(result.reward.obs_dim),  # type: ignore[arg-type]
            "action_space": space,
            "reward_family": config.reward_family,
            "reward_hidden": list(config.reward_hidden),
            "policy_hidden": list(config.policy_hidden),
            "activation": config.activation,
            "layer_norm": config.layer_norm,
            "gamma": config.gamma,
        },
        "hyperparameters": config.to_dict(),
        "beta_used": result.beta_used,
        "gradients": result.gradients,
        "data": dict(data),
        "device": str(device),
        "versions": package_versions(),
        "result": {
            "epochs": len(result.metrics),
            "final_metrics": result.metrics[-1] if result.metrics else None,
            "baselines": dict(baselines or {}),
        },
    }
    write_text(out / CONFIG_FILE, json.dumps(record, indent=2) + "\n")
    timings = {
        "samples_per_second": result.samples_per_second,
        "train_seconds": sum(result.epoch_seconds),
        "epoch_seconds": result.epoch_seconds,
    }
    write_text(out / TIMINGS_FILE, json.dumps(timings, indent=2) + "\n")


# --------------------------------------------------------------------------- several runs


def train_unit(
    table: bytes, table_path: str, algo: str, settings: dict[str, Any], device: str
) -> dict[str, Any]:
    """One run of a fan-out: a top-level, picklable function of plain arguments.

    The table arrives as bytes and the run folder leaves as bytes (``files``; the driver
    writes them), so a worker needs no shared filesystem. Pins torch to one thread
    (restored after) and seeds from ``settings["seed"]``.
    """
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with tempfile.TemporaryDirectory(prefix="pokerirl-run-") as scratch:
            path = Path(scratch) / "table.parquet"
            path.write_bytes(table)
            torch.manual_seed(settings["seed"])
            run = Path(scratch) / "run"
            train_into(
                read_table(path),
                run,
                algo=algo,
                config=AIRLConfig(**settings),
                device=device,
                table=table_path,
                table_file=path,
            )
            files = {f.name: f.read_bytes() for f in sorted(run.iterdir()) if f.is_file()}
    finally:
        torch.set_num_threads(threads)
    return {"files": files}


def _run_result(folder: Path) -> dict[str, Any]:
    """What :func:`summarize` needs of a finished run folder."""
    record = json.loads((folder / CONFIG_FILE).read_text(encoding="utf-8"))
    timings_path = folder / TIMINGS_FILE
    timings = json.loads(timings_path.read_text()) if timings_path.is_file() else {}
    return {
        "out": str(folder),
        "seed": record["hyperparameters"]["seed"],
        "metrics": [
            json.loads(line) for line in (folder / METRICS_FILE).read_text().splitlines() if line
        ],
        "baselines": json.loads((folder / BASELINES_FILE).read_text()),
        "samples_per_second": timings.get("samples_per_second", float("nan")),
        "train_rows": record["data"]["train_rows"],
        "val_rows": record["data"]["val_rows"],
    }


def train_runs(
    table: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    runs: int,
    algo: str = "hairl",
    config: AIRLConfig | None = None,
    device: str = "cpu",
    progress: bool = True,
    overwrite: bool = False,
    backend: Backend | None = None,
) -> RunSummary:
    """``runs`` runs of ``config`` with seeds ``seed + k`` into ``out_dir/run-<k>``, then
    ``summary.json`` and ``alignment_bands.png``. One run keeps the single-folder layout.

    Each run is a unit of :func:`pokerirl.execution.map_units` on ``backend`` (default: in
    this process): written atomically with a record of its settings and table, reused by a
    rerun with the same ones, recomputed when corrupt, refused when made with other
    settings unless ``overwrite``. Results do not depend on the backend.
    """
    if runs < 1:
        raise ValueError("--runs must be at least 1")
    config = config or AIRLConfig.for_algo(algo)
    if runs == 1:
        return train_table(
            table,
            out_dir,
            algo=algo,
            config=config,
            device=device,
            progress=progress,
            overwrite=overwrite,
        )
    resolve_device(device)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise RunError(f"{out} exists and is not a folder; choose another --out")
    if (out / CONFIG_FILE).is_file():
        raise RunError(f"{out} holds a single run; choose another --out for --runs {runs}")
    read_table(table)  # a bad table fails once, before any unit starts
    table_bytes = Path(table).read_bytes()
    shared = {"algo": algo, "device": device, "table": bytes_fingerprint(table_bytes)}
    unit_configs = [
        {**shared, "settings": {**config.to_dict(), "seed": config.seed + k}} for k in range(runs)
    ]
    folders = [out / f"run-{k}" for k in range(runs)]
    try:
        todo = [
            k
            for k in range(runs)
            if load_unit_folder(folders[k], unit_configs[k], overwrite=overwrite) is None
        ]
    except UnitConflict as error:
        raise RunError(str(error)) from None

    def save(index: int, result: dict[str, Any]) -> None:
        k = todo[index]
        files = dict(result["files"])
        timings = {TIMINGS_FILE: files.pop(TIMINGS_FILE)}
        save_unit_folder(folders[k], files, unit_configs[k], unhashed=timings)

    units = [
        (table_bytes, str(Path(table).resolve()), algo, unit_configs[k]["settings"], device)
        for k in todo
    ]
    map_units(
        train_unit,
        units,
        backend=backend or Backend(),
        progress=progress,
        desc=f"{algo} runs",
        reused=runs - len(todo),
        on_result=save,
        labels=[f"run-{k}" for k in todo],
    )
    for folder in folders:  # runs of an older pokerirl, reused: add their card
        if not (folder / "reward_card.json").is_file():
            write_reward_card(folder, table)
    results = [_run_result(folder) for folder in folders]
    summary = summarize(results)
    write_text(out / SUMMARY_FILE, json.dumps(summary, indent=2) + "\n")
    plot_bands(summary, out)
    first = results[0]
    return RunSummary(
        out_dir=out,
        metrics=first["metrics"],
        baselines=first["baselines"],
        samples_per_second=float(np.nanmean([r["samples_per_second"] for r in results])),
        train_rows=first["train_rows"],
        val_rows=first["val_rows"],
        runs=tuple(results),
    )


def summarize(results: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Mean and sample std (ddof 1) over runs of each scalar metric per epoch and of each
    baseline."""
    metrics = [r["metrics"] for r in results]
    keys = [k for k, v in metrics[0][0].items() if isinstance(v, int | float) and k != "epoch"]
    by_metric = {}
    for key in keys:
        values = np.array([[m[key] for m in run] for run in metrics], dtype=float)
        by_metric[key] = {"mean": values.mean(0).tolist(), "std": _std(values).tolist()}
    by_baseline = {}
    for key in results[0]["baselines"]:
        values = np.array([[r["baselines"][key]] for r in results], dtype=float)
        by_baseline[key] = {"mean": float(values.mean()), "std": float(_std(values)[0])}
    return {
        "runs": len(results),
        "seeds": [r["seed"] for r in results],
        "epochs": [m["epoch"] for m in metrics[0]],
        "metrics": by_metric,
        "baselines": by_baseline,
    }


def _std(values: np.ndarray) -> np.ndarray:
    return values.std(0, ddof=1) if len(values) > 1 else np.zeros(values.shape[1:])


# --------------------------------------------------------------------------- folders


def check_destination(out: Path, *, overwrite: bool) -> None:
    """Refuse an ``out`` that is a file, or a non-empty folder unless ``overwrite``."""
    if out.exists() and not out.is_dir():
        raise RunError(f"{out} exists and is not a folder; choose another --out")
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise RunError(f"{out} already holds files (a finished run?); pass --overwrite to replace")


@contextmanager
def staged_folder(out: Path, *, overwrite: bool) -> Iterator[Path]:
    """Yield a new hidden folder beside ``out``; on success it replaces ``out``.

    A failure or an interruption deletes it and leaves ``out`` as it was (a kill -9 leaves
    the hidden ``.<name>.*.tmp`` folder behind, never a change to ``out``).
    """
    check_destination(out, overwrite=overwrite)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        folder = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
    except OSError as error:
        raise RunError(f"{out}: cannot write there ({error.strerror or error})") from None
    make_shareable(folder)
    try:
        yield folder
        if out.is_dir() and any(out.iterdir()):
            old = out.parent / f".{out.name}.{uuid.uuid4().hex}.old"
            os.replace(out, old)
            os.replace(folder, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(folder, out)  # onto nothing, or onto an empty folder
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise


# --------------------------------------------------------------------------- loading


def load_run_config(run_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """The ``config.json`` of a run (format 1 or 2), checked; ``RunError`` naming the file."""
    path = Path(run_dir) / CONFIG_FILE
    if not path.is_file() and (Path(run_dir) / SUMMARY_FILE).is_file():
        raise RunError(f"{run_dir} holds several runs: choose one, e.g. {run_dir}/run-0")
    if not path.is_file():
        raise RunError(f"no {CONFIG_FILE} in {run_dir}: not a training run folder")
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise RunError(f"{path}: not readable JSON ({first_line(error)})") from None
    if not isinstance(record, dict):
        raise RunError(f"{path}: must hold a JSON object, got {type(record).__name__}")
    version = record.get("format_version")
    if version not in (1, FORMAT_VERSION):
        raise RunError(f"{path}: unsupported format_version {version!r}")
    arch = record.get("architecture")
    if not isinstance(arch, dict):
        raise RunError(f"{path}: lacks an 'architecture' object")
    problem = _architecture_problem(arch)
    if problem:
        raise RunError(f"{path}: architecture: {problem}")
    return record


def _architecture_problem(arch: Mapping[str, Any]) -> str | None:
    def is_int(x: Any) -> bool:
        return isinstance(x, int) and not isinstance(x, bool)

    def widths(x: Any) -> bool:
        return isinstance(x, list) and bool(x) and all(is_int(w) and w >= 1 for w in x)

    space = arch.get("action_space")
    if not is_int(arch.get("obs_dim")) or arch["obs_dim"] < 1:
        return "'obs_dim' must be a positive integer"
    if not isinstance(space, dict) or space.get("type") not in ("discrete", "box"):
        return "'action_space' must be {type: discrete|box, ...}"
    if space["type"] == "discrete" and not (is_int(space.get("num_actions"))):
        return "'action_space.num_actions' must be an integer"
    if space["type"] == "box":
        low, high = space.get("low"), space.get("high")
        if not (_numbers(low) and _numbers(high) and len(low) == len(high)):
            return "'action_space.low' and 'high' must be equal-length lists of numbers"
    for key in ("reward_hidden", "policy_hidden"):
        if not widths(arch.get(key)):
            return f"{key!r} must be a non-empty list of positive integers"
    if arch.get("activation", "relu") not in ACTIVATIONS:
        return f"'activation' must be one of {', '.join(ACTIVATIONS)}"
    if not isinstance(arch.get("layer_norm", False), bool):
        return "'layer_norm' must be true or false"
    if arch.get("reward_family", "state_action") not in REWARD_FAMILIES:
        return f"'reward_family' must be one of {', '.join(REWARD_FAMILIES)}"
    gamma = arch.get("gamma", 0.99)
    if not isinstance(gamma, int | float) or isinstance(gamma, bool):
        return "'gamma' must be a number"
    return None


def _numbers(value: Any) -> bool:
    return (
        isinstance(value, list)
        and bool(value)
        and all(isinstance(x, int | float) and not isinstance(x, bool) for x in value)
    )


def build_from_record(record: Mapping[str, Any]) -> tuple[nn.Module, nn.Module]:
    """Untrained reward and policy nets of the architecture a run's ``config.json`` records
    (drawn from torch's global RNG, as :func:`~pokerirl.irl.nets.build_nets` draws them)."""
    arch = record["architecture"]
    space = arch["action_space"]
    spec = NetSpec(
        reward_hidden=tuple(arch["reward_hidden"]),
        policy_hidden=tuple(arch["policy_hidden"]),
        activation=arch.get("activation", "relu"),
        layer_norm=arch.get("layer_norm", False),
        reward_family=arch.get("reward_family", "state_action"),
        gamma=float(arch.get("gamma", 0.99)),
    )
    discrete = space["type"] == "discrete"
    return build_nets(
        spec,
        obs_dim=arch["obs_dim"],
        action_dim=space["num_actions"] if discrete else len(space["low"]),
        discrete=discrete,
        low=None if discrete else space["low"],
        high=None if discrete else space["high"],
    )


def _load_state(module: nn.Module, path: Path) -> None:
    if not path.is_file():
        raise RunError(f"checkpoint not found: {path}")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception:  # noqa: BLE001 - torch raises many kinds (and advises unsafe loading)
        raise RunError(
            f"{path}: not a readable PyTorch state_dict (corrupt or truncated)"
        ) from None
    if not isinstance(state, dict):
        raise RunError(f"{path}: holds a {type(state).__name__}, not a state_dict")
    try:
        module.load_state_dict(state)
    except (RuntimeError, TypeError, ValueError) as error:
        raise RunError(f"{path} does not match its {CONFIG_FILE}: {first_line(error)}") from None
    module.eval()


def load_policy(run_dir: str | os.PathLike[str]) -> nn.Module:
    """The trained policy of a run (on CPU, in eval mode)."""
    _, policy = build_from_record(load_run_config(run_dir))
    _load_state(policy, Path(run_dir) / POLICY_FILE)
    return policy


class RewardFunction:
    """A batched learned reward r(obs, actions) -> rewards.

    ``obs`` is (B, obs_dim) of any numeric dtype (the poker tables' uint8 is fine);
    ``actions`` are ids (B,) for discrete action spaces, values (B, k) for box ones.
    numpy in gives float32 numpy out; torch tensors in give a float32 tensor out.
    By default it is the transferable reward g(s, a) (all of f for the ``state_action``
    family); with ``full`` (shaped family) it is f(s, a, s') and needs ``next_obs`` and ``done``.
    """

    def __init__(self, net: nn.Module, *, num_actions: int | None, full: bool = False) -> None:
        self.net = net.eval()
        self.obs_dim = int(net.obs_dim)  # type: ignore[arg-type]
        self.num_actions = num_actions  # None: continuous actions
        self.full = full

    def __call__(
        self,
        obs: np.ndarray | Tensor,
        actions: np.ndarray | Tensor,
        next_obs: np.ndarray | Tensor | None = None,
        done: np.ndarray | Tensor | None = None,
    ) -> Any:
        as_numpy = isinstance(obs, np.ndarray)
        tensor = lambda x: torch.as_tensor(np.asarray(x) if as_numpy else x)  # noqa: E731
        obs_t, actions_t = tensor(obs), tensor(actions)
        if obs_t.ndim != 2 or obs_t.shape[1] != self.obs_dim:
            raise ValueError(f"obs must be (B, {self.obs_dim}), got {tuple(obs_t.shape)}")
        if len(actions_t) != len(obs_t):
            raise ValueError("obs and actions must have the same batch size")
        extra: tuple[Tensor, ...] = ()
        if self.full:
            if next_obs is None or done is None:
                raise ValueError("the full shaped reward needs next_obs and done")
            extra = (tensor(next_obs).float(), tensor(done).bool())
        with torch.inference_mode():
            if self.num_actions is not None:
                vectors = torch.nn.functional.one_hot(actions_t.long(), self.num_actions)
            else:
                vectors = actions_t.reshape(len(actions_t), -1)
            rewards = self.net(obs_t.float(), vectors.float(), *extra)
        return rewards.numpy() if as_numpy else rewards


def load_reward(run_dir: str | os.PathLike[str], *, full: bool = False) -> RewardFunction:
    """The learned reward of a run as a batched callable r(obs, action_ids) -> rewards.

    g(s, a) by default (see :class:`RewardFunction`); every problem with the folder is a
    :class:`RunError` (a ``ValueError``) of one line naming the file.
    """
    record = load_run_config(run_dir)
    reward, _ = build_from_record(record)
    _load_state(reward, Path(run_dir) / REWARD_FILE)
    space = record["architecture"]["action_space"]
    num_actions = space["num_actions"] if space["type"] == "discrete" else None
    return RewardFunction(reward, num_actions=num_actions, full=full)
