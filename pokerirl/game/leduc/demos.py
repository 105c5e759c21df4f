"""Demonstrations on Leduc hold'em: hands of a strategy (the CFR+ expert) against itself or
another, played on the batch engine, every decision of the chosen positions as arrays; an
``.npz`` file with a JSON header, no pickle (what ``pokerirl leduc synth`` writes).

Each decision row has the actor's 36-d observation, the legal actions (the four columns of
:data:`~pokerirl.game.leduc.batch.ACTIONS`), the action, the actor's observation at its next
decision (or at the end of the hand), whether it was the actor's last decision, the chips it
won then (``reward``, 0 before its last decision), the hand, the position and the
information-set row (``keys[row]``: the truth behind the data is the strategy at that key).

>>> from pokerirl.game.leduc.rules import RLCARD
>>> from pokerirl.game.leduc.strategy import uniform_strategy
>>> demos = synthesize(RLCARD, uniform_strategy(RLCARD), hands=50, seed=0)
>>> demos.obs.shape[1], int(demos.hand.max()), bool(demos.done.any())
(36, 49, True)
"""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pokerirl.errors import InputError
from pokerirl.game.leduc.batch import LeducBatch
from pokerirl.game.leduc.infosets import info_sets
from pokerirl.game.leduc.rules import LeducRules, get_rules
from pokerirl.game.leduc.strategy import Strategy, sha256, to_json

FORMAT = "leduc-demonstrations"
ARRAYS = ("obs", "legal", "action", "next_obs", "done", "reward", "hand", "position", "row")
MAX_HANDS = 10_000_000  # about 25M decisions: 2 GB of observations (the CLI offers the same)


@dataclass(frozen=True, kw_only=True, eq=False)
class Demonstrations:
    """Decisions of ``hands`` hands, in the order they were played (hand by hand within a
    step of the batch)."""

    rules: LeducRules
    hands: int
    seed: int
    expert_sha256: str
    opponent_sha256: str
    obs: np.ndarray  # n x 36 float32
    legal: np.ndarray  # n x 4 bool
    action: np.ndarray  # n int64, ACTIONS index
    next_obs: np.ndarray  # n x 36 float32
    done: np.ndarray  # n bool
    reward: np.ndarray  # n float32: chips won, at the actor's last decision
    hand: np.ndarray  # n int64
    position: np.ndarray  # n int64
    row: np.ndarray  # n int64: info_sets(rules).keys[row]

    def __len__(self) -> int:
        return len(self.action)

    @property
    def keys(self) -> list[str]:
        """Each decision's information-set key."""
        names = info_sets(self.rules).keys
        return [names[r] for r in self.row.tolist()]

    def header(self) -> dict[str, object]:
        return {
            "format": FORMAT, "version": 1, "rules": self.rules.name, "hands": self.hands,
            "seed": self.seed, "expert_sha256": self.expert_sha256,
            "opponent_sha256": self.opponent_sha256, "decisions": len(self),
        }  # fmt: skip


def strategy_sha256(rules: LeducRules, strategy: Strategy) -> str:
    """The sha256 of the strategy file ``strategy`` would be (the solve folder's sha256)."""
    return sha256(to_json(rules, strategy))


def synthesize(
    rules: LeducRules,
    expert: Strategy,
    *,
    hands: int,
    seed: int,
    opponent: Strategy | None = None,
    positions: tuple[int, ...] = (0, 1),
) -> Demonstrations:
    """``hands`` hands: ``expert`` in position ``hand % 2``, ``opponent`` in the other (None:
    the expert plays itself and both seats are the expert's); the expert's decisions in
    ``positions`` (0 acts first in the first round) are recorded. Seeded: the same
    arguments give the same arrays."""
    if not 1 <= hands <= MAX_HANDS:
        raise InputError(f"hands must lie in 1..{MAX_HANDS:,}, got {hands}")
    sets = info_sets(rules)
    self_play = opponent is None  # then every decision is the expert's
    opponent = expert if opponent is None else opponent
    cumulative = [np.cumsum(sets.probabilities(s), axis=1) for s in (expert, opponent)]
    rng = np.random.default_rng(seed)
    batch = LeducBatch.dealt(rules, hands, rng)
    expert_seat = np.arange(hands) % 2
    steps: list[tuple[np.ndarray, ...]] = []
    while not batch.over.all():
        live = np.flatnonzero(~batch.over)
        actor = batch.to_act[live]
        rows = sets.rows_of(batch.node[live], batch.cards[live])
        is_expert = (actor == expert_seat[live]) | self_play
        table = np.where(is_expert[:, None], cumulative[0][rows], cumulative[1][rows])
        draw = rng.random(len(live))[:, None] * table[:, -1:]  # rows sum to 1 up to rounding
        choice = np.minimum((table <= draw).sum(axis=1), 3)
        keep = is_expert & np.isin(actor, positions)
        obs = batch.observations(batch.to_act.clip(0))[live]
        legal = batch.legal()[live]
        steps.append((live[keep], actor[keep], rows[keep], obs[keep], legal[keep], choice[keep]))
        actions = np.zeros(hands, dtype=np.int64)
        actions[live] = choice
        batch.step(actions)
    hand, position, row, obs, legal, action = (np.concatenate(c) for c in zip(*steps, strict=True))
    payoffs = batch.payoffs()
    final = [batch.observations(np.full(hands, p)) for p in (0, 1)]
    # The next decision of the same actor in the same hand: rows sorted by (hand, position),
    # play order kept (stable), so the next row of a pair is its next decision.
    order = np.lexsort((position, hand))
    n = len(hand)
    following = np.full(n, -1, dtype=np.int64)
    same = (hand[order][1:] == hand[order][:-1]) & (position[order][1:] == position[order][:-1])
    following[order[:-1][same]] = order[1:][same]
    done = following < 0
    end_obs = np.where(position[:, None] == 0, final[0][hand], final[1][hand])
    next_obs = np.where(done[:, None], end_obs, obs[following.clip(0)])
    reward = np.where(done, payoffs[hand, position], 0.0)
    return Demonstrations(
        rules=rules, hands=hands, seed=seed, expert_sha256=strategy_sha256(rules, expert),
        opponent_sha256=strategy_sha256(rules, opponent), obs=obs.astype(np.float32),
        legal=legal, action=action.astype(np.int64), next_obs=next_obs.astype(np.float32),
        done=done, reward=reward.astype(np.float32), hand=hand.astype(np.int64),
        position=position.astype(np.int64), row=row.astype(np.int64),
    )  # fmt: skip


def save(demos: Demonstrations, path: str | Path) -> None:
    """Write ``path`` (.npz: the arrays and ``header``, a JSON string). Fixed zip dates: the
    same demonstrations give the same bytes."""
    from pokerirl.atomic import write_bytes

    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        header = np.array(json.dumps(demos.header(), sort_keys=True))
        for name, value in (("header", header), *((a, getattr(demos, a)) for a in ARRAYS)):
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            data = io.BytesIO()
            np.lib.format.write_array(data, np.ascontiguousarray(value), allow_pickle=False)
            archive.writestr(info, data.getvalue())
    write_bytes(path, buffer.getvalue())


def load(path: str | Path) -> Demonstrations:
    """Read a file of :func:`save` (an :class:`InputError` naming it for anything else)."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            arrays = {name: archive[name] for name in ("header", *ARRAYS)}
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as error:
        raise InputError(f"{path}: not a Leduc demonstrations file ({error})") from None
    try:
        header = json.loads(str(arrays.pop("header").item()))
        if header.get("format") != FORMAT:
            raise ValueError(f"format {header.get('format')!r}")
        rules = get_rules(str(header["rules"]))
        fields = {k: header[k] for k in ("hands", "seed", "expert_sha256", "opponent_sha256")}
    except (ValueError, KeyError, AttributeError) as error:
        raise InputError(f"{path}: not a Leduc demonstrations file ({error})") from None
    n = len(arrays["action"])
    if any(len(a) != n for a in arrays.values()) or arrays["obs"].shape[1:] != (36,):
        raise InputError(f"{path}: arrays of different lengths or widths")
    if n and not 0 <= arrays["row"].min() <= arrays["row"].max() < len(info_sets(rules).keys):
        raise InputError(f"{path}: information-set rows out of range for {rules.name}")
    return Demonstrations(rules=rules, **fields, **arrays)
