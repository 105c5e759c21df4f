"""The strength encoding inside a 20,000-hand DQN run by street (seed 0, own play), three runs;
`python parts2.py table` or `count` (the turn table read or the turn counted). Output: parts2.txt."""
import os, sys
os.environ["OMP_NUM_THREADS"]="1"
import time, torch
torch.set_num_threads(1)
import pokerirl.agents.dqn as D
import pokerirl.game.encodings as E
import pokerirl.game.equity as Q
from pokerirl.game import make_agent
from pokerirl.game.equity import forget_recent_states, use_turn_table
use_turn_table(sys.argv[1] == "table")
acc = {}
def wrap(owner, name, label):
    orig = getattr(owner, name)
    def f(*a, **k):
        t = time.process_time(); r = orig(*a, **k); acc[label] = acc.get(label, 0) + time.process_time() - t; return r
    setattr(owner, name, f)
wrap(D.DQNLearner, "update", "update")
wrap(E.StrengthEncoding, "encode", "encode")
wrap(E, "range_equity", "equity")
for n in ("river_equity", "turn_equity", "flop_equity"):
    wrap(Q, n, n)
for enc in ["strength"] * 3:
    D.train_dqn(D.DQNConfig(), hands=1000, seed=1, opponent=make_agent("random"), encoding=enc)
    forget_recent_states(); acc.clear()
    t = time.process_time()
    l = D.train_dqn(D.DQNConfig(), hands=20000, seed=0, opponent=make_agent("random"), encoding=enc)
    tot = time.process_time() - t
    print(enc, f"total {tot:.3f}", {k: round(v, 3) for k, v in acc.items()})
