"""Issue 31's measurements: does a learned poker reward recover a known expert?

On a synthetic month (two threshold bots, ``pokerirl synth``), H-AIRL is trained on what
``ingest`` keeps of it (the showdown hands) and scored against the truth: the same month
written with ``--reveal-all``, where every hand is kept, folds included, and every row is the
expert's true action. For each (encoding, reward weight decay), ``--runs`` runs:

* the reward card of each run on the truth table: f's argmax = the expert (``agree_expert``),
  its raise share in the top equity bucket (``argmax_share_by_strength``), its fold share and
  how often it folds a weak hand facing a bet;
* behaviour cloning (the same policy net, α = 1, no adversary): its validation alignment on
  the showdown table (``baselines.json``), and its agreement with the expert on the truth
  table when trained on the showdown table's training hands;
* then ``pokerirl transfer`` on each run of the chosen configuration: DQNs on f (``raw`` and
  ``advantage``, the transform under which f's argmax is the optimal policy) with the strength
  encoding, ``--dqn-seeds`` each, and on run 0 with the 72-d encoding; f's argmax and π
  greedy; all judged against random, head to head against each bot and against each bot's
  rule.

With ``--source MONTH`` (real IRC data, e.g. the April 1995 sample) there is no truth: the
runs are trained and scored on the month's own table (every expert row), and BC on the truth
is left out; the rest is the same.

Everything is resumable (the runs and agents are store units) and seeded: the same arguments
give the same numbers. Writes ``OUT/recovery.json`` and prints a markdown summary.

    python benchmarks/recovery.py --out /work/exp [--hands 30000] [--runs 3] [--jobs 2]
        [--dqn-seeds 0-2] [--dqn-hands 50000] [--no-transfer] [--source MONTH]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pokerirl.datasets.ingest import ingest_table
from pokerirl.execution import Backend
from pokerirl.game.encodings import get_encoding
from pokerirl.game.synth import write_synthetic_month
from pokerirl.irl import load_config, train
from pokerirl.poker import read_table, train_runs
from pokerirl.poker.reward_card import STRENGTH_EDGES, CardStates, reward_card
from pokerirl.poker.reward_sources import load_reward_source
from pokerirl.seeds import parse_seeds

CONFIGS = (("strength", 0.0), ("rlcard", 0.0), ("strength", 5e-3), ("rlcard", 5e-3))
CHOSEN = ("strength", 0.0)  # the new defaults with --encoding strength: the DQNs' reward


def tables(out: Path, hands: int, seed: int) -> tuple[Path, Path]:
    """The showdown-only table (what ingest keeps) and the truth table of one month."""
    found = []
    for name, reveal in (("showdown", False), ("truth", True)):
        table = out / f"{name}.parquet"
        if not table.is_file():
            month = write_synthetic_month(out / f"month-{name}", hands=hands, seed=seed,
                                          reveal_all=reveal)  # fmt: skip
            ingest_table([month], table)
        found.append(table)
    return found[0], found[1]


def weak_facing_fold(card_states: CardStates, best: np.ndarray) -> float:
    """Share of weak states (equity < 25%) facing a bet where ``best`` folds."""
    legal = card_states.decisions.legal_mask
    weak = (card_states.strength < STRENGTH_EDGES[0]) & legal[:, 0]
    return float((best[weak] == 2).mean()) if weak.any() else float("nan")


def score_run(run: Path, truth: CardStates) -> dict[str, Any]:
    reward = load_reward_source(run)
    card = reward_card(reward, truth)
    values = reward.action_values(truth.decisions)
    best = np.where(truth.decisions.legal_mask, values, -np.inf).argmax(axis=1)
    baselines = json.loads((run / "baselines.json").read_text())
    final = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()][-1]
    return {
        "agree_expert": card.agree_expert,
        "argmax_share": card.argmax_share,
        "top_bucket_raise": card.argmax_share_by_strength[-1]["raise"],
        "expert_top_bucket_raise": (card.expert_share_by_strength or [{}])[-1].get("raise"),
        "weak_facing_bet_fold": weak_facing_fold(truth, best),
        "agree_legal_majority": card.agree_legal_majority,
        "val_reward_alignment": final["val_reward_alignment"],
        "val_alignment": final["val_alignment"],
        "bc_val": baselines["bc"],
    }


def bc_on_truth(showdown: Path, truth: Path, encoding: str, decay: float, seed: int) -> float:
    """BC (α = 1, no adversary) on the showdown table's training hands, scored on every
    state of the truth table."""
    config = load_config("hairl", overrides={"reward_weight_decay": decay, "seed": seed})
    data = read_table(showdown, encoding=get_encoding(encoding))
    train_data, val_data, _ = data.split(val_fraction=config.val_fraction, seed=seed)
    torch.manual_seed(seed)
    result = train(train_data, val_data, config=dataclasses.replace(config, alpha=1.0),
                   adversarial=False, progress=False)  # fmt: skip
    every = read_table(truth, encoding=get_encoding(encoding))
    with torch.no_grad():
        log_pi = result.policy(every.obs, every.legal_mask)
    return float((log_pi.argmax(-1) == every.actions).float().mean())


def mean_se(values: list[float]) -> dict[str, float]:
    array = np.asarray(values, dtype=float)
    se = float(array.std(ddof=1) / np.sqrt(array.size)) if array.size > 1 else 0.0
    return {"mean": float(array.mean()), "se": se, "n": int(array.size)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--hands", type=int, default=30_000)
    parser.add_argument("--month-seed", type=int, default=0)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--dqn-seeds", default="0-2")
    parser.add_argument("--dqn-hands", type=int, default=50_000)
    parser.add_argument("--no-transfer", action="store_true")
    parser.add_argument("--transforms", default="raw,advantage", help="the DQNs' reward transforms")
    parser.add_argument("--transfer-runs", type=int, default=None,
                        help="transfer on the first N runs only (default: all)")
    parser.add_argument("--transfer-only", action="store_true",
                        help="keep OUT/recovery.json's IRL numbers; redo the transfer only")
    parser.add_argument("--source", type=Path, help="a real IRC month instead of a synthetic one")
    args = parser.parse_args()
    torch.set_num_threads(1)
    started = time.time()
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    if args.source is None:
        showdown, truth_table = tables(out, args.hands, args.month_seed)
    else:  # real data: the table is its own (and only) judge
        showdown = truth_table = out / "expert.parquet"
        if not showdown.is_file():
            ingest_table([args.source], showdown)
    truth = CardStates.from_table(truth_table)
    backend = Backend(jobs=args.jobs)
    source = None if args.source is None else str(args.source)
    found: dict[str, Any] = {"hands": args.hands, "month_seed": args.month_seed,
                             "runs": args.runs, "configs": {}, "source": source}  # fmt: skip
    if args.transfer_only:
        found = json.loads((out / "recovery.json").read_text())
    for encoding, decay in () if args.transfer_only else CONFIGS:
        key = f"{encoding}, decay {decay:g}"
        folder = out / "runs" / f"hairl-{encoding}-decay{decay:g}"
        print(f"[{time.time() - started:6.0f}s] {key}: {args.runs} runs -> {folder}", flush=True)
        config = load_config("hairl", overrides={"reward_weight_decay": decay})
        train_runs(showdown, folder, runs=args.runs, config=config, progress=False,
                   backend=backend, encoding=get_encoding(encoding))  # fmt: skip
        runs = [folder / f"run-{k}" for k in range(args.runs)] if args.runs > 1 else [folder]
        scores = [score_run(run, truth) for run in runs]
        bc_truth = None  # no truth on real data
        if args.source is None:
            bc_truth = [bc_on_truth(showdown, truth_table, encoding, decay, k)
                        for k in range(args.runs)]  # fmt: skip
        summary = {name: mean_se([s[name] for s in scores]) for name in (
            "agree_expert", "top_bucket_raise", "weak_facing_bet_fold", "agree_legal_majority",
            "val_reward_alignment", "val_alignment", "bc_val")}  # fmt: skip
        summary["bc_truth"] = None if bc_truth is None else mean_se(bc_truth)
        summary["fold_share"] = mean_se([s["argmax_share"]["fold"] for s in scores])
        summary["raise_share"] = mean_se([s["argmax_share"]["raise"] for s in scores])
        found["configs"][key] = {"per_run": scores, "bc_truth_per_run": bc_truth, **summary}
        found["expert_top_bucket_raise"] = scores[0]["expert_top_bucket_raise"]
        (out / "recovery.json").write_text(json.dumps(found, indent=2) + "\n")
    if not args.no_transfer:
        transfer_all(out, args, found, started)
    (out / "recovery.json").write_text(json.dumps(found, indent=2) + "\n")
    figure(found, out / "recovery.png")
    print(markdown(found))


def transfer_all(out: Path, args: argparse.Namespace, found: dict[str, Any],
                 started: float) -> None:  # fmt: skip
    from pokerirl.studies.poker.transfer import TransferConfig, run_transfer

    encoding, decay = CHOSEN
    folder = out / "runs" / f"hairl-{encoding}-decay{decay:g}"
    runs = [folder / f"run-{k}" for k in range(args.runs)] if args.runs > 1 else [folder]
    runs = runs[: args.transfer_runs]
    seeds = tuple(parse_seeds(args.dqn_seeds))
    rows: dict[str, dict[str, list[float]]] = {}
    for dqn_encoding in ("strength", "rlcard"):
        chosen = runs if dqn_encoding == "strength" else runs[:1]
        for run in chosen:
            target = out / "transfer" / f"{run.name}-{dqn_encoding}"
            print(f"[{time.time() - started:6.0f}s] transfer {run} ({dqn_encoding} DQNs)",
                  flush=True)  # fmt: skip
            config = TransferConfig(transforms=tuple(args.transforms.split(",")), seeds=seeds,
                                    hands=args.dqn_hands, encoding=dqn_encoding)  # fmt: skip
            result = run_transfer(run, target, config, backend=Backend(jobs=args.jobs))
            for row in result.rows:
                label = row.label if row.kind != "dqn" or row.transform is None else (
                    f"DQN ({dqn_encoding}) on f, {row.label}")  # fmt: skip
                if row.label == "sparse DQN":
                    label = f"sparse DQN ({dqn_encoding})"
                if dqn_encoding == "rlcard" and row.kind != "dqn":
                    continue  # the same rows as the strength transfer's
                if (row.kind == "fixed" or row.label == "sparse DQN") and run != chosen[0]:
                    continue  # the same agents in every run's transfer: counted once
                entry = rows.setdefault(label, {})
                for name, values in (
                    ("vs_random", row.vs_random),
                    *((f"vs_{bot}", vs) for bot, vs in row.vs_experts.items()),
                    *((f"agree_{rule}", share) for rule, share in row.agreement.items()),
                    ("raise_share", [s["raise"] for s in row.action_shares]),
                    ("fold_share", [s["fold"] for s in row.action_shares]),
                ):
                    entry.setdefault(name, []).extend(values)
    found["transfer"] = {label: {k: mean_se(v) for k, v in entry.items()}
                         for label, entry in rows.items()}  # fmt: skip


def figure(found: dict[str, Any], path: Path) -> None:
    """recovery.png: f's argmax = the expert and its top-bucket raise share per (encoding,
    decay), mean ± SE over runs with each run's point; then the transfer rows' agreement with
    each bot's rule and raise share."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    panels = 3 if "transfer" in found else 2
    fig = Figure(figsize=(5 * panels, 4.8), dpi=100)
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, panels)
    keys = list(found["configs"])
    titles = {"agree_expert": "f's argmax = the expert (all states)",
              "top_bucket_raise": "f raises, top equity bucket"}  # fmt: skip
    for ax, (name, title) in zip(axes, titles.items(), strict=False):
        means = [100 * found["configs"][k][name]["mean"] for k in keys]
        errors = [100 * found["configs"][k][name]["se"] for k in keys]
        ax.bar(range(len(keys)), means, yerr=errors, capsize=3, color="C0", alpha=0.7)
        for i, key in enumerate(keys):
            points = [100 * run[name] for run in found["configs"][key]["per_run"]]
            ax.plot([i] * len(points), points, "k.", markersize=4)
        ax.set_xticks(range(len(keys)), [k.replace(", ", "\n") for k in keys], fontsize=8)
        ax.set(title=title, ylabel="% of states (bars: mean ± SE over runs; dots: runs)")
    bc_truth = found["configs"][keys[0]]["bc_truth"]
    if bc_truth is not None:  # synthetic months only: real data have no truth table
        axes[0].axhline(100 * bc_truth["mean"], color="C2", ls="--",
                        label="BC, strength (on the same truth)")  # fmt: skip
        axes[0].legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    if found.get("expert_top_bucket_raise") is not None:
        axes[1].axhline(100 * found["expert_top_bucket_raise"], color="C3", ls="--",
                        label="the expert")  # fmt: skip
        axes[1].legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    if panels == 3:
        ax = axes[2]
        rows = {k: v for k, v in found["transfer"].items() if "agree_tightbot" in v}
        names = list(rows)
        for j, (metric, label) in enumerate((("agree_tightbot", "= tightbot rule"),
                                             ("agree_loosebot", "= loosebot rule"),
                                             ("raise_share", "raise share"))):  # fmt: skip
            ax.barh([i + 0.27 * j for i in range(len(names))],
                    [100 * rows[n][metric]["mean"] for n in names], height=0.27,
                    xerr=[100 * rows[n][metric]["se"] for n in names], label=label)  # fmt: skip
        ax.set_yticks([i + 0.27 for i in range(len(names))], names, fontsize=7)
        ax.invert_yaxis()
        ax.set(title="agents vs random: decisions (%)", xlabel="% of decisions (± SE)")
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3)
    fig.tight_layout()
    fig.savefig(path, format="png", metadata={"Software": None})


def markdown(found: dict[str, Any]) -> str:
    def pct(stat: dict[str, float] | None) -> str:
        return "-" if stat is None else f"{100 * stat['mean']:.1f} ± {100 * stat['se']:.1f}"

    source = found.get("source")
    what = (
        f"Synthetic month: {found['hands']:,} hands (seed {found['month_seed']}); H-AIRL on the "
        "showdown-only table, scored on every state of the --reveal-all table"
        if source is None
        else f"Real data ({source}): H-AIRL on its table, scored on every row of it"
    )
    lines = [
        f"{what}; {found['runs']} runs per row (seeds 0..{found['runs'] - 1}). ± is the SE "
        "over runs.",
        "",
        "| encoding, decay | argmax = expert (%) | top-bucket raise (%) | fold share (%) | "
        "folds weak facing bet (%) | = legal majority (%) | BC val (%) | BC on truth (%) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for key, row in found["configs"].items():
        lines.append(
            f"| {key} | {pct(row['agree_expert'])} | {pct(row['top_bucket_raise'])} | "
            f"{pct(row['fold_share'])} | {pct(row['weak_facing_bet_fold'])} | "
            f"{pct(row['agree_legal_majority'])} | {pct(row['bc_val'])} | "
            f"{pct(row['bc_truth'])} |"
        )
    lines.append(f"\nThe expert raises in {100 * found['expert_top_bucket_raise']:.1f}% of the top "
                 "equity bucket.")  # fmt: skip
    if "transfer" in found:
        lines += ["", "| agent | vs random (mbb/h) | vs tightbot | vs loosebot | = tightbot rule "
                  "(%) | = loosebot rule (%) | raise share (%) | fold share (%) |",
                  "|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for label, row in found["transfer"].items():
            def mbb(name: str, row: dict[str, Any] = row) -> str:
                return f"{row[name]['mean']:+,.0f} ± {row[name]['se']:,.0f}" if name in row else "-"

            lines.append(
                f"| {label} (n={row['vs_random']['n']}) | {mbb('vs_random')} | "
                f"{mbb('vs_tightbot')} | {mbb('vs_loosebot')} | {pct(row['agree_tightbot'])} | "
                f"{pct(row['agree_loosebot'])} | {pct(row['raise_share'])} | "
                f"{pct(row['fold_share'])} |"
            )
    return "\n".join(lines)


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
