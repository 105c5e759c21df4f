"""A solve folder: the CFR+ average strategy after N iterations (``strategy.json``), its
exploitability curve (``curve.csv``, ``curve.png``) and ``summary.json``; what
``pokerirl leduc solve`` writes."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from pokerirl.atomic import write_text
from pokerirl.errors import PokerIRLError, Remedy
from pokerirl.game.leduc.cfr import CFRPlus, CurvePoint
from pokerirl.game.leduc.exact import MILLI
from pokerirl.game.leduc.rules import LeducRules
from pokerirl.game.leduc.strategy import sha256, to_json

FILES = ("strategy.json", "curve.csv", "curve.png", "summary.json")


@dataclass(frozen=True, kw_only=True)
class Solved:
    """What a solve found: the last exploitability (chips per hand), its seconds, the
    strategy file's sha256."""

    rules: LeducRules
    iterations: int
    exploitability: float
    seconds: float
    sha256: str

    def line(self) -> str:
        return (
            f"leduc {self.rules.name}: CFR+ {self.iterations:,} iterations, exploitability "
            f"{self.exploitability * MILLI:.4f} milli-chips per hand ({self.seconds:.1f} s)"
        )


def check_out(out: Path, *, overwrite: bool) -> None:
    """Refuse ``out`` if it is a file, or a folder that holds anything (unless ``overwrite``)."""
    if out.exists() and not out.is_dir():
        raise PokerIRLError(f"{out} exists and is not a folder", remedy=Remedy.ELSEWHERE)
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise PokerIRLError(f"{out} is not empty", remedy=Remedy.REPLACE)


def solve(
    rules: LeducRules,
    *,
    iterations: int,
    out: Path,
    every: int = 10,
    overwrite: bool = False,
    progress: Callable[[CurvePoint], None] | None = None,
) -> Solved:
    """Run CFR+ and write the folder ``out`` (refused if it holds anything, unless
    ``overwrite``)."""
    check_out(out, overwrite=overwrite)
    solver = CFRPlus(rules)
    start = time.perf_counter()
    curve = solver.run(iterations, every=every, progress=progress)
    seconds = time.perf_counter() - start
    out.mkdir(parents=True, exist_ok=True)
    text = to_json(rules, solver.average(), iterations=iterations)
    write_text(out / "strategy.json", text)
    rows = [f"{p.iteration},{p.exploitability:.12f}" for p in curve]
    write_text(out / "curve.csv", "iteration,exploitability_chips\n" + "\n".join(rows) + "\n")
    _plot(rules, curve, out / "curve.png")
    solved = Solved(
        rules=rules, iterations=iterations, exploitability=curve[-1].exploitability,
        seconds=seconds, sha256=sha256(text),
    )  # fmt: skip
    summary = {
        "rules": rules.name, "iterations": iterations, "every": every,
        "exploitability_chips": solved.exploitability,
        "exploitability_milli_chips": solved.exploitability * MILLI,
        "strategy_sha256": solved.sha256,
    }  # fmt: skip
    write_text(out / "summary.json", json.dumps(summary, indent=1) + "\n")  # no time: same bytes
    return solved


def _plot(rules: LeducRules, curve: list[CurvePoint], path: Path) -> None:
    from matplotlib.figure import Figure  # no pyplot: no global state, no display

    from pokerirl.figures import finish

    figure = Figure(figsize=(7, 4))
    axes = figure.add_subplot()
    axes.loglog([p.iteration for p in curve], [p.exploitability * MILLI for p in curve],
                label=f"CFR+ ({rules.name})")  # fmt: skip
    finish(axes, title=f"Leduc hold'em ({rules.name} rules): CFR+ average strategy",
           xlabel="iteration", ylabel="exploitability (milli-chips per hand)")  # fmt: skip
    figure.savefig(path, format="png", dpi=100, bbox_inches="tight")
