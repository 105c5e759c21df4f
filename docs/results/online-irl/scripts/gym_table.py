"""The Gymnasium tables of docs/results/online-irl/README.md (issue 43), from the run folders.

python gym_table.py ROOT ENV...  (ROOT: ENV-ALGO-MODE/ of `pokerirl gym irl --runs 3`, beside
its `/usr/bin/time -f "%e %U %S"` output in PREFIX-ALGO-MODE.time; rl/ENV/ALGO-MODE-K/run-0
of `pokerirl gym rl --reward-run ENV-ALGO-MODE/run-K --runs 1` and rl/ENV/env/run-K of
`--env-reward --runs 3`)
"""

import json
import statistics
import sys
from pathlib import Path

PREFIX = {"HalfCheetah-v4": "HC", "Pendulum-v1": "Pendulum", "MountainCar-v0": "MC"}


def ms(xs, fmt=".1f"):
    if not xs:
        return "—"
    if len(xs) == 1:
        return f"{xs[0]:{fmt}} (1 run)"
    return f"{statistics.mean(xs):{fmt}} ± {statistics.stdev(xs):{fmt}}"


def last(path):
    return json.loads(path.read_text().strip().splitlines()[-1])


def final(folder):
    config = folder / "run-0" / "config.json"
    return json.loads(config.read_text())["final_return"] if config.is_file() else None


def main(root: Path, envs) -> None:
    print("| env | algo | mode | IRL policy return | EPIC (random-reward EPIC) | val alignment / MSE "
          "| RL on learned reward, final true return | wall s | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for env in envs:
        for algo in ("airl", "gail", "hairl"):
            for mode in ("offline", "online"):
                irl = root / f"{env}-{algo}-{mode}"
                if not (irl / "summary.json").is_file():
                    continue
                rets, epic, rnd, val = [], [], [], []
                key = None
                for k in range(3):
                    m = last(irl / f"run-{k}" / "metrics.jsonl")
                    rets.append(m["eval_return"])
                    key = "val_alignment" if "val_alignment" in m else "val_mse"
                    val.append(m[key])
                    q = json.loads((irl / f"run-{k}" / "reward_quality.json").read_text())
                    epic.append(q["epic"])
                    rnd.append(q["epic_random_baseline"])
                rl = [f for k in range(3)
                      if (f := final(root / "rl" / env / f"{algo}-{mode}-{k}")) is not None]
                t = (root / f"{PREFIX[env]}-{algo}-{mode}.time")
                wall, cpu = "", ""
                if t.is_file():
                    e, u, s = map(float, t.read_text().split()[-3:])
                    wall, cpu = f"{e:.0f}", f"{u + s:.0f}"
                print(f"| {env} | {algo} | {mode} | {ms(rets)} | {ms(epic, '.3f')} "
                      f"({statistics.mean(rnd):.3f}) | {key} {ms(val, '.3f')} | {ms(rl)} "
                      f"| {wall} | {cpu} |")
        envr = [f for k in range(3) if (c := root / "rl" / env / "env" / f"run-{k}" / "config.json")
                .is_file() and (f := json.loads(c.read_text())["final_return"]) is not None]
        print(f"| {env} | env reward | | | | | {ms(envr)} | | |")


if __name__ == "__main__":
    main(Path(sys.argv[1]), sys.argv[2:])
