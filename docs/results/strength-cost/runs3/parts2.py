"""The strength encoding inside a 20,000-hand DQN run by street (seed 0, own play), three runs;
`python parts2.py table` or `count` (the turn table read or the turn counted). Output: parts2.txt."""
import sys

import pokerirl.agents.dqn as D
import pokerirl.game.encodings as E
import pokerirl.game.equity as Q
from _timing import acc, runs, wrap

Q.use_turn_table(sys.argv[1] == "table")
wrap(D.DQNLearner, "update", "update")
wrap(E.StrengthEncoding, "encode", "encode")
wrap(E, "range_equity", "equity")
for n in ("river_equity", "turn_equity", "flop_equity"):
    wrap(Q, n, n)
for enc, tot, _ in runs(["strength"] * 3):
    print(enc, f"total {tot:.3f}", {k: round(v, 3) for k, v in acc.items()})
