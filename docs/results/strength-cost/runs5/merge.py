"""The recorded calls (states.pkl) merged k at a time into fewer, larger calls: CPU s of the
strength encoding, best of 3 replays."""
import pickle, time, numpy as np
import pokerirl.game.encodings as E
from pokerirl.game.equity import use_turn_table, forget_recent_states
from pokerirl.game.encodings import RawStates
use_turn_table(True)
rec = pickle.load(open("states.pkl", "rb"))
enc = E.StrengthEncoding()
def merge(group):
    return RawStates(cards=np.concatenate([s.cards for s in group]), raise_nums=np.concatenate([s.raise_nums for s in group]), legal_mask=np.concatenate([s.legal_mask for s in group]))
for s in rec[:20]: enc.encode(s)
print("sizes", np.percentile([len(s.cards) for s in rec],[0,25,50,75,100]))
for k in (1, 2, 4, 16, 324):
    calls = [merge(rec[i:i+k]) for i in range(0, len(rec), k)]
    best = 9
    for _ in range(3):
        forget_recent_states(); t = time.process_time()
        for s in calls: enc.encode(s)
        best = min(best, time.process_time() - t)
    print(k, len(calls), round(best, 4))
