"""Min and median total CPU of N 20,000-hand DQN runs per encoding (seed 0, own play), interleaved."""
import sys, os
os.environ["OMP_NUM_THREADS"] = "1"
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "runs3"))
from _timing import acc, runs, wrap
import numpy as np
import pokerirl.game.encodings as E
from pokerirl.game.equity import use_turn_table
use_turn_table(True)
wrap(E.StrengthEncoding, "encode", "encode")
n = int(sys.argv[1]); encs = sys.argv[2:] or ["rlcard", "strength"]
tot = {e: [] for e in encs}; encode = []
for enc, t, l in runs(encs * n):
    tot[enc].append(t)
    if enc == "strength": encode.append(acc.get("encode", 0))
for e in encs: print(e, f"min {min(tot[e]):.3f} median {np.median(tot[e]):.3f}", end="  ")
print(f"encode min {min(encode):.3f} median {np.median(encode):.3f}", f"ratio of mins {min(tot['rlcard'])/min(tot['strength']):.3f}")
