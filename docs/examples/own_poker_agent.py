"""Your own poker agent in a pokerirl match (``pokerirl.play_match``).

An agent is any object with a ``name`` and ``act(obs, legal_mask, rng)`` deciding for a
whole batch of hands at once (``pokerirl.Agent``): ``obs`` (B, 72) in RLCard's limit-holdem
encoding, ``legal_mask`` (B, 4) over (call, raise, fold, check), ``rng`` the only
randomness to use; it returns (B,) legal action ids. Set ``sees_cards = True`` to be given
``cards=`` too: (B, 7) hole cards then the board shown, -1 beyond (cards are 0..51, suit
major, A 2 .. K within a suit: ``card % 13`` is the rank, 0 the ace).

    python docs/examples/own_poker_agent.py --hands 100000

Prints one ``result:`` line per opponent, in milli-big-blinds per hand with its standard error.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np

import pokerirl
from pokerirl.holdem import CALL, CHECK, FOLD, RAISE  # action ids, RLCard's order


@dataclass(frozen=True, kw_only=True)
class PairsAndAces:
    """Raise with a pocket pair or an ace, fold other hands to a bet preflop, else call down."""

    name: str = "pairs-and-aces"
    sees_cards: bool = True  # ask the engine for the cards

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator, *,
            cards: np.ndarray) -> np.ndarray:  # fmt: skip
        rank = cards[:, :2] % 13
        strong = (rank[:, 0] == rank[:, 1]) | (rank == 0).any(axis=1)
        preflop = cards[:, 2] < 0  # no board card shown yet
        passive = np.where(legal_mask[:, CALL], CALL, CHECK)
        weak_vs_bet = ~strong & preflop & legal_mask[:, CALL]
        action = np.where(weak_vs_bet, FOLD, passive)
        return np.where(strong & legal_mask[:, RAISE], RAISE, action).astype(np.int64)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hands", type=int, default=100_000, help="hands per match (even)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    mine = PairsAndAces()
    assert isinstance(mine, pokerirl.Agent)  # the protocol is structural: no base class
    for opponent in ("random", "call", "tightbot"):  # or an agent folder, reward:RUN, ...
        # Duplicate deals: each deal is played from both seats, which cancels most card luck.
        result = pokerirl.play_match(mine, pokerirl.resolve_agent(opponent), hands=args.hands,
                                     seed=args.seed)  # fmt: skip
        print(f"result: {mine.name} vs {opponent}: {result.mbb_per_hand:+.0f} "
              f"± {result.std_error:.0f} mbb/h over {result.hands} hands")


if __name__ == "__main__":
    main()
