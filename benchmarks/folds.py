"""Issue 32's measurements: learning from the hands that end in a fold (docs/folds.md).

On a synthetic month (two threshold bots, ``pokerirl synth``) the logs hide the cards of every
hand that ends in a fold. Three tables of the same month:

* ``showdown``: what ``ingest`` keeps by default (``--folds drop``);
* ``imputed``: ``ingest --folds impute`` (the hidden cards drawn from a posterior);
* ``truth``: the month written with ``--reveal-all`` (every hand, its true cards): the oracle.

Stages (``--stages``, all by default):

* ``quality``: the imputed cards against the truth. For every hidden player, the true pair's
  rank under the posterior (1 = the most likely of the ~1,225 pairs), and the log-likelihood of
  the true pair against a uniform prior's, in bits; per EM round of the behaviour model, and
  beside the posterior under the bots' own (known) policy, the best any π_B could do.
* ``irl``: ``--runs`` H-AIRL runs (``--encoding strength``, the recovery defaults) on each
  table, each scored by its reward card on every state of the truth table: f's argmax fold
  share, how often it folds a weak hand (equity < 25%) facing a bet, and its agreement with
  the expert's true actions.
* ``transfer``: ``pokerirl transfer`` on each run of the showdown and imputed tables: DQNs on f
  (``strength``, ``--transforms``: advantage by default), their fold share and agreement
  with each bot's rule.
* ``real``: the April 1995 sample imputed: counts, entropies, and H-AIRL runs on it with and
  without the imputed folds, their reward cards on the imputed table.
* ``speed``: the April 1995 sample imputed on one core (throughput in hands/s).

Resumable (tables, runs and agents are kept) and seeded. Writes ``OUT/folds.json`` and prints
markdown.

    python benchmarks/folds.py --out /work/fexp [--hands 30000] [--runs 3] [--jobs 2]
        [--dqn-seeds 0-2] [--dqn-hands 50000] [--stages quality,irl,transfer,real,speed]
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
import pyarrow.parquet as pq
import torch

from pokerirl.datasets.ingest import ingest_table
from pokerirl.execution import Backend
from pokerirl.game.encodings import get_encoding
from pokerirl.game.synth import DEFAULT_PLAYERS, visible_strength, write_synthetic_month
from pokerirl.holdem import CALL, CARD_INDEX, CHECK, FOLD, RAISE
from pokerirl.irl import load_config
from pokerirl.poker import train_runs
from pokerirl.poker.folds import ImputeConfig
from pokerirl.poker.impute import (
    NUM_PAIRS,
    PAIRS,
    Behaviour,
    Expansion,
    Hidden,
    Imputation,
    fit_behaviour,
    impute,
    log_likelihoods,
    posterior,
    split_table,
)
from pokerirl.poker.reward_card import STRENGTH_EDGES, CardStates, reward_card
from pokerirl.poker.reward_sources import load_reward_source
from pokerirl.seeds import parse_seeds

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT.parent / "shared" / "irc-sample" / "holdem" / "199504"
TABLES = ("showdown", "imputed", "truth")
ENCODING = "strength"


# --------------------------------------------------------------------------- tables


def months(out: Path, hands: int, seed: int) -> tuple[Path, Path]:
    """The month as the logs show it, and the same month with every card shown."""
    found = []
    for name, reveal in (("showdown", False), ("truth", True)):
        folder = out / f"month-{name}"
        month = folder / "holdem" / "200101"
        if not (month / "hdb").is_file():
            write_synthetic_month(folder, hands=hands, seed=seed, reveal_all=reveal)
        found.append(month)
    return found[0], found[1]


def plain_tables(out: Path, logs: Path, truth_month: Path) -> None:
    for name, month in (("showdown", logs), ("truth", truth_month)):
        if not (out / f"{name}.parquet").is_file():
            ingest_table([month], out / f"{name}.parquet")


def imputed_table(out: Path, logs: Path, config: ImputeConfig, name: str = "imputed",
                  on_round: Any = None) -> tuple[Imputation | None, float]:  # fmt: skip
    """``ingest --folds impute`` of the logs (kept when there), with the imputation object."""
    target = out / f"{name}.parquet"
    if target.is_file() and on_round is None:
        return None, float("nan")
    captured: dict[str, Any] = {}

    def step(table: Any, *, progress: bool) -> Any:
        split = split_table(table)
        if on_round is None:
            imputation = impute(table, config, progress=progress)
        else:  # the same fit, watched round by round
            behaviour, rounds = fit_behaviour(split, config, progress=False,
                                              on_round=lambda r, b: on_round(split, r, b))
            imputation = impute(table, config, behaviour=behaviour, progress=progress)
            summary = dataclasses.replace(imputation.summary, rounds=tuple(rounds))
            imputation = dataclasses.replace(imputation, summary=summary)
        captured["imputation"] = imputation
        return imputation.result()

    started = time.perf_counter()
    ingest_table([logs], target, folds=step)
    return captured["imputation"], time.perf_counter() - started


# --------------------------------------------------------------------------- quality


def true_pairs(truth: Path, hidden: Hidden) -> np.ndarray:
    """(P,) the index in PAIRS of each hidden player's true cards, from the truth table."""
    table = pq.read_table(truth, columns=["hand_id", "player", "hole_cards"])
    lookup = np.full((52, 52), -1)
    lookup[PAIRS[:, 0], PAIRS[:, 1]] = lookup[PAIRS[:, 1], PAIRS[:, 0]] = np.arange(NUM_PAIRS)
    cards = {}
    for hand, player, text in zip(*(table.column(c).to_pylist() for c in table.column_names),
                                  strict=True):  # fmt: skip
        a, b = text.split()
        cards[(hand, player)] = lookup[CARD_INDEX[a], CARD_INDEX[b]]
    return np.array([cards[(h, p)] for h, p in zip(hidden.hand_id, hidden.player, strict=True)])


def bots_log_likelihood(hidden: Hidden) -> np.ndarray:
    """(P, 1326) Σ log P(a_t | c) under the bots' own policy (game/synth.py): the posterior
    the best behaviour model would give."""
    by_nick = {p.nick: p for p in DEFAULT_PLAYERS}
    found = np.zeros((hidden.players, NUM_PAIRS))
    for d in range(0, len(hidden.owner), 64):
        index = np.arange(d, min(d + 64, len(hidden.owner)))
        owner = hidden.owner[index]
        board = np.where(hidden.board[index] >= 0, hidden.board[index], 0)  # later streets unused
        hole = np.broadcast_to(PAIRS, (len(index), NUM_PAIRS, 2)).reshape(-1, 2)
        street = (hidden.board[index] >= 0).sum(1)
        street = np.searchsorted(np.array([0, 3, 4, 5]), street)
        score = visible_strength(hole, np.repeat(board, NUM_PAIRS, axis=0)).reshape(
            len(index), NUM_PAIRS, 4)[np.arange(len(index)), :, street]  # fmt: skip
        bots = [by_nick[str(hidden.player[o])] for o in owner]
        raise_above = np.array([b.raise_above for b in bots])[:, None]
        call_above = np.array([b.call_above for b in bots])[:, None]
        noise = np.array([b.noise for b in bots])[:, None]
        cap = np.array([b.max_raises for b in bots])
        facing = hidden.legal_mask[index, CALL][:, None]
        can_raise = (hidden.raise_nums[index, street] < cap)[:, None]
        go_on = np.where(facing, CALL, CHECK)
        rule = np.where(can_raise & (score > raise_above), RAISE,
                        np.where(~facing | (score > call_above), go_on, FOLD))  # fmt: skip
        action = hidden.action[index][:, None]
        options = 1 + facing.astype(int) + can_raise.astype(int)
        legal_option = (action == go_on) | ((action == FOLD) & facing) | ((action == RAISE)
                                                                         & can_raise)  # fmt: skip
        p = (1 - noise) * (rule == action) + noise / options * legal_option
        np.add.at(found, owner, np.log(np.maximum(p, 1e-300)))
    return found


def quality(hidden: Hidden, loglik: np.ndarray, true: np.ndarray) -> dict[str, float]:
    post = posterior(hidden, loglik)
    rows = np.arange(hidden.players)
    lp = post.log_probs[rows, true]
    ok = post.explained & np.isfinite(lp)
    # Mid-rank: a pair tied with the truth counts half (the bots' rule ties many pairs).
    rank = (post.log_probs > lp[:, None]).sum(axis=1) + ((post.log_probs == lp[:, None]).sum(
        axis=1) + 1) / 2  # fmt: skip
    gain = (lp + np.log(post.support)) / np.log(2)
    return {
        "players": int(hidden.players),
        "explained": int(post.explained.sum()),
        "true_pair_impossible": int((post.explained & ~np.isfinite(lp)).sum()),
        "rank_mean": float(rank[ok].mean()),
        "rank_median": float(np.median(rank[ok])),
        "rank_top10pct": float((rank[ok] <= 0.1 * post.support[ok]).mean()),
        "support_mean": float(post.support[ok].mean()),
        "gain_bits_mean": float(gain[ok].mean()),
        "entropy_bits_mean": float(np.nanmean(post.entropy_bits[ok])),
        "uniform_bits_mean": float(np.log2(post.support[ok]).mean()),
    }


def quality_stage(out: Path, logs: Path, truth: Path, config: ImputeConfig,
                  name: str) -> dict[str, Any]:  # fmt: skip
    """The posterior's quality after each EM round of π_B, and under the bots' policy."""
    rounds: list[dict[str, Any]] = []
    cache: dict[str, Any] = {}

    def on_round(split: Any, r: int, behaviour: Behaviour) -> None:
        hidden = split.hidden
        if "true" not in cache:
            cache["true"] = true_pairs(truth, hidden)
            cache["expansion"] = Expansion(hidden, behaviour.encoding)
        loglik = log_likelihoods(hidden, behaviour, expansion=cache["expansion"])
        rounds.append({"round": r, **quality(hidden, loglik, cache["true"])})
        print(f"  quality {name} round {r}: {rounds[-1]}", flush=True)

    imputation, seconds = imputed_table(out, logs, config, name=name, on_round=on_round)
    assert imputation is not None
    hidden = imputation.split.hidden
    bots = quality(hidden, bots_log_likelihood(hidden), cache["true"])
    return {"config": dataclasses.asdict(config), "seconds": seconds, "rounds": rounds,
            "bots_policy": bots, "summary": imputation.summary.to_json()}  # fmt: skip


# --------------------------------------------------------------------------- IRL


def weak_facing_fold(states: CardStates, best: np.ndarray) -> float:
    legal = states.decisions.legal_mask
    weak = (states.strength < STRENGTH_EDGES[0]) & legal[:, CALL]
    return float((best[weak] == FOLD).mean())


def score_run(run: Path, truth: CardStates) -> dict[str, Any]:
    reward = load_reward_source(run)
    card = reward_card(reward, truth)
    values = reward.action_values(truth.decisions)
    best = np.where(truth.decisions.legal_mask, values, -np.inf).argmax(axis=1)
    final = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()][-1]
    return {
        "agree_expert": card.agree_expert,
        "fold_share": card.argmax_share["fold"],
        "raise_share": card.argmax_share["raise"],
        "weak_facing_bet_fold": weak_facing_fold(truth, best),
        "top_bucket_raise": card.argmax_share_by_strength[-1]["raise"],
        "expert_fold_share": (card.expert_share or {}).get("fold"),
        "expert_weak_facing_bet_fold": weak_facing_fold(truth, truth.expert),  # type: ignore[arg-type]
        "val_reward_alignment": final["val_reward_alignment"],
        "val_alignment": final["val_alignment"],
        "baselines": json.loads((run / "baselines.json").read_text()),
    }


def runs_of(folder: Path, runs: int) -> list[Path]:
    return [folder / f"run-{k}" for k in range(runs)] if runs > 1 else [folder]


def irl_stage(out: Path, args: argparse.Namespace, truth: CardStates) -> dict[str, Any]:
    found: dict[str, Any] = {}
    backend = Backend(jobs=args.jobs)
    config = load_config("hairl")
    for name in TABLES:
        folder = out / "runs" / f"hairl-{name}"
        started = time.time()
        train_runs(out / f"{name}.parquet", folder, runs=args.runs, config=config,
                   progress=False, backend=backend, encoding=get_encoding(ENCODING))  # fmt: skip
        scores = [score_run(run, truth) for run in runs_of(folder, args.runs)]
        found[name] = {"per_run": scores, "seconds": time.time() - started,
                       **{key: mean_se([s[key] for s in scores]) for key in (
                           "agree_expert", "fold_share", "raise_share", "weak_facing_bet_fold",
                           "top_bucket_raise", "val_reward_alignment", "val_alignment")}}
        print(f"  irl {name}: {json.dumps(without_runs(found[name]))}", flush=True)
    return found


def transfer_stage(out: Path, args: argparse.Namespace) -> dict[str, Any]:
    from pokerirl.studies.poker.transfer import TransferConfig, run_transfer

    seeds = tuple(parse_seeds(args.dqn_seeds))
    found: dict[str, Any] = {}
    for name in ("showdown", "imputed"):
        rows: dict[str, dict[str, list[float]]] = {}
        for run in runs_of(out / "runs" / f"hairl-{name}", args.runs):
            config = TransferConfig(transforms=tuple(args.transforms.split(",")), seeds=seeds,
                                    hands=args.dqn_hands,
                                    encoding=ENCODING)  # fmt: skip
            result = run_transfer(run, out / "transfer" / f"{name}-{run.name}", config,
                                  backend=Backend(jobs=args.jobs))  # fmt: skip
            for row in result.rows:
                entry = rows.setdefault(row.label, {})
                for key, values in (
                    ("vs_random", row.vs_random),
                    *((f"vs_{bot}", vs) for bot, vs in row.vs_experts.items()),
                    *((f"agree_{rule}", share) for rule, share in row.agreement.items()),
                    ("raise_share", [s["raise"] for s in row.action_shares]),
                    ("fold_share", [s["fold"] for s in row.action_shares]),
                ):
                    entry.setdefault(key, []).extend(values)
        found[name] = {label: {k: mean_se(v) for k, v in entry.items()}
                       for label, entry in rows.items()}  # fmt: skip
        print(f"  transfer {name}: {json.dumps(found[name])[:2000]}", flush=True)
    return found


# --------------------------------------------------------------------------- the real sample


def real_stage(out: Path, args: argparse.Namespace) -> dict[str, Any]:
    from pokerirl.poker.impute import ingest_imputed

    real = out / "real"
    real.mkdir(exist_ok=True)
    drop, imputed = real / "drop.parquet", real / "imputed.parquet"
    if not drop.is_file():
        ingest_table([SAMPLE], drop)
    if not imputed.is_file():
        ingest_imputed([SAMPLE], imputed, ImputeConfig())
    summary = json.loads((real / "imputed.summary.json").read_text())
    found: dict[str, Any] = {"summary": summary, "cards": {}}
    states = CardStates.from_table(imputed)
    config = load_config("hairl")
    for name, table in (("drop", drop), ("imputed", imputed)):
        folder = real / "runs" / f"hairl-{name}"
        train_runs(table, folder, runs=args.runs, config=config, progress=False,
                   backend=Backend(jobs=args.jobs),
                   encoding=get_encoding(ENCODING))  # fmt: skip
        cards = [reward_card(load_reward_source(run), states)
                 for run in runs_of(folder, args.runs)]  # fmt: skip
        found["cards"][name] = {
            "per_run": [json.loads(c.to_json()) for c in cards],
            "fold_share": mean_se([c.argmax_share["fold"] for c in cards]),
            "raise_share": mean_se([c.argmax_share["raise"] for c in cards]),
            "agree_expert": mean_se([c.agree_expert or 0.0 for c in cards]),
            "agree_expert_observed": mean_se([(c.by_part or {})["observed"]["agree_expert"]
                                              for c in cards]),
            "agree_expert_imputed": mean_se([(c.by_part or {})["imputed"]["agree_expert"]
                                             for c in cards]),
        }
        print(f"  real {name}: {json.dumps(without_runs(found['cards'][name]))}", flush=True)
    return found


def speed_stage(out: Path) -> dict[str, Any]:
    """The April 1995 sample imputed on one core, twice: the whole ``ingest --folds impute``
    (parse, π_B's fit and EM rounds, the final posterior, the table) and one posterior pass
    alone (every hidden decision x 1,326 pairs through π_B)."""
    from pokerirl.poker.impute import ingest_imputed

    torch.set_num_threads(1)
    times, passes, summary = [], [], None
    captured: dict[str, Any] = {}

    def step(table: Any, *, progress: bool) -> Any:
        captured["imputation"] = impute(table, ImputeConfig(behaviour_rounds=0))
        return captured["imputation"].result()

    for k in range(2):
        started = time.perf_counter()
        summary = ingest_imputed([SAMPLE], out / f"speed-{k}.parquet", ImputeConfig())
        times.append(time.perf_counter() - started)
        ingest_table([SAMPLE], out / f"speed-pass-{k}.parquet", folds=step)
        imputation = captured["imputation"]
        started = time.perf_counter()
        log_likelihoods(imputation.split.hidden, imputation.behaviour)
        passes.append(time.perf_counter() - started)
    assert summary is not None and summary.folds is not None
    seconds, one_pass = float(np.median(times)), float(np.median(passes))
    return {"seconds": times, "hands_imputed": summary.folds.imputed_hands,
            "hands_per_second": summary.folds.imputed_hands / seconds,
            "decisions": summary.folds.imputed_decisions,
            "posterior_passes": len(summary.folds.rounds),  # EM rounds' passes and the last
            "one_pass_seconds": passes,
            "one_pass_hands_per_second": summary.folds.imputed_hands / one_pass,
            "one_pass_states_per_second": summary.folds.imputed_decisions * NUM_PAIRS / one_pass,
            "load": os.getloadavg()}  # fmt: skip


# --------------------------------------------------------------------------- report


def without_runs(row: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in row.items() if k != "per_run"}


def mean_se(values: list[float]) -> dict[str, float]:
    array = np.asarray(values, dtype=float)
    se = float(array.std(ddof=1) / np.sqrt(array.size)) if array.size > 1 else 0.0
    sd = float(array.std(ddof=1)) if array.size > 1 else 0.0
    return {"mean": float(array.mean()), "se": se, "sd": sd, "min": float(array.min()),
            "max": float(array.max()), "n": int(array.size)}  # fmt: skip


def markdown(found: dict[str, Any]) -> str:
    def pct(stat: dict[str, float]) -> str:
        return f"{100 * stat['mean']:.1f} ± {100 * stat['sd']:.1f}"

    lines = []
    if "irl" in found:
        lines += [
            f"Synthetic month: {found['hands']:,} hands (seed {found['month_seed']}); "
            f"{found['runs']} H-AIRL runs per table (seeds 0..{found['runs'] - 1}), "
            "--encoding strength; scored on every state of the --reveal-all table. ± is the "
            "sample standard deviation over runs.",
            "",
            "| train table | fold share of the argmax | folds weak hands facing a bet | "
            "argmax = expert, all states |",
            "|---|---|---|---|",
        ]
        for name in TABLES:
            row = found["irl"][name]
            lines.append(f"| {name} | {pct(row['fold_share'])} | "
                         f"{pct(row['weak_facing_bet_fold'])} | {pct(row['agree_expert'])} |")
    if "quality" in found:
        lines += ["", "| posterior | mean rank of the truth | median | top 10% | gain over "
                  "uniform (bits) | entropy (bits) |", "|---|---|---|---|---|---|"]  # fmt: skip
        for name, q in found["quality"].items():
            for row in [*q["rounds"], {"round": "bots' policy", **q["bots_policy"]}]:
                lines.append(
                    f"| {name}, round {row['round']} | {row['rank_mean']:.0f} of "
                    f"{row['support_mean']:.0f} | {row['rank_median']:.0f} | "
                    f"{100 * row['rank_top10pct']:.1f}% | {row['gain_bits_mean']:+.3f} | "
                    f"{row['entropy_bits_mean']:.2f} of {row['uniform_bits_mean']:.2f} |"
                )
    return "\n".join(lines)


QUALITY_CONFIGS = {
    "imputed": ImputeConfig(),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--hands", type=int, default=30_000)
    parser.add_argument("--month-seed", type=int, default=0)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--dqn-seeds", default="0-2")
    parser.add_argument("--dqn-hands", type=int, default=50_000)
    parser.add_argument("--transforms", default="advantage",
                        help="the DQNs' reward transforms (raw f makes always-call: recovery.md)")
    parser.add_argument("--stages", default="quality,irl,transfer,real,speed")
    parser.add_argument("--quality-configs", default=None,
                        help='JSON {"name": {ImputeConfig fields}} to compare (quality only)')
    args = parser.parse_args()
    torch.set_num_threads(1)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    stages = set(args.stages.split(","))
    result_file = out / "folds.json"
    found: dict[str, Any] = json.loads(result_file.read_text()) if result_file.is_file() else {}
    found.update(hands=args.hands, month_seed=args.month_seed, runs=args.runs)
    mine: set[str] = set()

    def save() -> None:  # merged: stages may run in several processes at once
        merged = json.loads(result_file.read_text()) if result_file.is_file() else {}
        merged.update({key: found[key] for key in (*mine, "hands", "month_seed", "runs")})
        found.update(merged)
        result_file.write_text(json.dumps(merged, indent=2) + "\n")

    if stages & {"quality", "irl", "transfer"}:
        logs, truth_month = months(out, args.hands, args.month_seed)
        plain_tables(out, logs, truth_month)
    if "quality" in stages:
        mine.add("quality")
        configs = QUALITY_CONFIGS
        if args.quality_configs:
            configs = {k: ImputeConfig(**v) for k, v in json.loads(args.quality_configs).items()}
        for name, config in configs.items():
            found.setdefault("quality", {})[name] = quality_stage(
                out, logs, out / "truth.parquet", config, name)
            save()
    if stages & {"irl", "transfer"}:
        imputed_table(out, logs, ImputeConfig())
    for stage in ("irl", "transfer", "real", "speed"):
        if stage not in stages or (stage in ("real", "speed") and not SAMPLE.is_dir()):
            continue
        mine.add(stage)
        if stage == "irl":
            found["irl"] = irl_stage(out, args, CardStates.from_table(out / "truth.parquet"))
        elif stage == "transfer":
            found["transfer"] = transfer_stage(out, args)
        elif stage == "real":
            found["real"] = real_stage(out, args)
        else:
            found["speed"] = speed_stage(out)
        save()
    print(markdown(found))


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
