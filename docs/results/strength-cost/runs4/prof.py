"""Replays the recorded calls (rec.py: states.pkl) alone, three times, then once profiled."""
import pickle, time, cProfile, pstats
import pokerirl.game.encodings as E
from pokerirl.game.equity import use_turn_table, forget_recent_states
use_turn_table(True)
rec = pickle.load(open("states.pkl", "rb"))
enc = E.StrengthEncoding()
for s in rec[:20]: enc.encode(s)
for _ in range(3):
    forget_recent_states(); t = time.process_time()
    for s in rec: enc.encode(s)
    print("replay", round(time.process_time() - t, 4))
forget_recent_states()
cProfile.run("for s in rec: enc.encode(s)", "p.out")
pstats.Stats("p.out").sort_stats("tottime").print_stats(25)
