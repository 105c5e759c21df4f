"""Replays the recorded calls of a 20,000-hand DQN run (states.pkl, from ../runs4/rec.py) alone:
CPU time of the strength encoding, min and median of 12 replays (argument: how many)."""
import pickle, time, numpy as np, sys
import pokerirl.game.encodings as E, pokerirl.game.equity as Q
Q.use_turn_table(True)
rec = pickle.load(open("states.pkl", "rb"))
enc = E.StrengthEncoding()
for s in rec[:20]: enc.encode(s)
ts = []
for _ in range(int(sys.argv[1]) if len(sys.argv) > 1 else 12):
    Q.forget_recent_states(); t = time.process_time()
    for s in rec: enc.encode(s)
    ts.append(time.process_time() - t)
print(f"replay min {min(ts)*1e3:.1f} ms median {np.median(ts)*1e3:.1f}")
