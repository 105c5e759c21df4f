"""The poker DQN table of docs/results/online-irl/README.md (issue 43), from the run folders.

python poker_table.py ROOT  (ROOT: off/, on/ (pokerirl train --runs 3), dqn/<name>-<k>,
match/<agent>-vs-<bot>.log (pokerirl match --format json), lbr/<agent>/report.json)
"""

import json
import statistics
import sys
from pathlib import Path


def ms(xs):
    xs = [float(x) for x in xs]
    return f"{statistics.mean(xs):+.0f} ± {statistics.stdev(xs):.0f}" if len(xs) > 1 else f"{xs[0]:+.0f}"


def ms3(xs):
    return f"{statistics.mean(xs):.3f} ± {statistics.stdev(xs):.3f}"


def match(root, agent, bot):
    text = (root / "match" / f"{agent}-vs-{bot}.log").read_text()
    return json.loads(text[text.index("{"):])


def main(root: Path) -> None:
    print("| reward | reward = expert (card) | DQN follows its reward | DQN vs random (training eval) "
          "| DQN vs TightBot, mbb/h | DQN vs LooseBot, mbb/h | DQN LBR, mbb/h |")
    print("|---|---|---|---|---|---|---|")
    for name in ("off", "on", "sparse"):
        agents = [f"{name}-{k}" for k in range(3)]
        card = ""
        if name != "sparse":
            card = ms3([json.loads((root / name / f"run-{k}" / "reward_card.json").read_text())
                        ["agree_expert"] for k in range(3)])
        finals = [json.loads((root / "dqn" / a / "config.json").read_text())["final"] for a in agents]
        follows = ms3([f["follows_reward"] for f in finals]) if name != "sparse" else ""
        rnd = ms([f["eval"]["random"]["mbb_per_hand"] for f in finals])
        vs = {}
        for bot in ("tightbot", "loosebot"):
            res = [match(root, a, bot) for a in agents]
            vs[bot] = (ms([r["mbb_per_hand"] for r in res]) + " (per agent: "
                       + ", ".join(f"{r['mbb_per_hand']:+.0f} ± {r['std_error']:.0f}" for r in res) + ")")
        lbr = [json.loads((root / "lbr" / a / "report.json").read_text()) for a in agents
               if (root / "lbr" / a / "report.json").is_file()]
        lbr_s = (ms([r["lbr_mbb_per_hand"] for r in lbr]) + " (per agent: "
                 + ", ".join(f"{r['lbr_mbb_per_hand']:+.0f} ± {r['lbr_std_error']:.0f}" for r in lbr)
                 + ")") if lbr else "not run"
        if len(lbr) not in (0, 3):
            lbr_s += f" [{len(lbr)} of 3]"
        print(f"| {name} | {card} | {follows} | {rnd} | {vs['tightbot']} | {vs['loosebot']} | {lbr_s} |")
    t = match(root, "tightbot", "loosebot")
    tl = root / "lbr" / "tightbot" / "report.json"
    tls = "not run"
    if tl.is_file():
        r = json.loads(tl.read_text())
        tls = f"{r['lbr_mbb_per_hand']:+.0f} ± {r['lbr_std_error']:.0f}"
    print(f"| TightBot itself | | | | 0 (itself) | {t['mbb_per_hand']:+.0f} ± {t['std_error']:.0f} | {tls} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
