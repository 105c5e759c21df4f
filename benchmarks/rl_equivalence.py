"""Do two RL backends learn the same? Compare the run folders of two ``pokerirl gym rl`` outputs.

Usage: python benchmarks/rl_equivalence.py SB3_DIR LOCKSTEP_DIR [NAME]

For each folder: the final true return and the area under the learning curve (the mean of the
curve's evaluation points, so on the return's scale) per run, mean ± sample std over runs. The
backends agree when the difference of means is within one pooled std and Welch's t-test gives
p > 0.05 (issue 19). Prints one Markdown row per measure.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
from scipy import stats


def per_run(folder: Path) -> tuple[list[float], list[float]]:
    finals, aucs = [], []
    for run in sorted(folder.glob("run-*"), key=lambda p: int(p.name.split("-")[1])):
        config = json.loads((run / "config.json").read_text())
        curve = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
        finals.append(float(config["final_return"]))
        aucs.append(float(np.mean([point["return_mean"] for point in curve])))
    if not finals:
        raise SystemExit(f"error: {folder}: no run-* folders")
    return finals, aucs


def row(name: str, a: list[float], b: list[float]) -> str:
    mean_a, mean_b = float(np.mean(a)), float(np.mean(b))
    std_a, std_b = float(np.std(a, ddof=1)), float(np.std(b, ddof=1))
    pooled = math.sqrt((std_a**2 + std_b**2) / 2)
    p = float(stats.ttest_ind(a, b, equal_var=False).pvalue) if pooled > 0 else 1.0
    agree = abs(mean_a - mean_b) <= pooled and p > 0.05
    return (f"| {name} | {mean_a:.1f} ± {std_a:.1f} | {mean_b:.1f} ± {std_b:.1f} | "
            f"{mean_b - mean_a:+.1f} ({pooled:.1f}) | {p:.2f} | {'yes' if agree else 'no'} |")


def main() -> None:
    if len(sys.argv) not in (3, 4):
        raise SystemExit(__doc__)
    sb3, lockstep = Path(sys.argv[1]), Path(sys.argv[2])
    name = sys.argv[3] if len(sys.argv) == 4 else sb3.name
    (f_sb3, auc_sb3), (f_lock, auc_lock) = per_run(sb3), per_run(lockstep)
    print("| measure | SB3 | lock-step | difference (pooled std) | Welch p | agree |")
    print("|---|---|---|---|---|---|")
    print(row(f"{name}, final return ({len(f_sb3)} / {len(f_lock)} runs)", f_sb3, f_lock))
    print(row(f"{name}, AUC", auc_sb3, auc_lock))
    print("per run, SB3:", [round(x, 1) for x in f_sb3])
    print("per run, lock-step:", [round(x, 1) for x in f_lock])


if __name__ == "__main__":
    main()
