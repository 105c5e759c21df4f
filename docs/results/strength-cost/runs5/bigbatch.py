"""Large batches (ingest, imputation, a whole run at once): random states of all streets, and
the recorded calls merged into one, best of 7 x 3 encodings."""
import numpy as np, timeit, pickle
import pokerirl.game.encodings as E, pokerirl.game.equity as Q
from pokerirl.game.encodings import RawStates
Q.use_turn_table(True)
rng = np.random.default_rng(1)
enc = E.StrengthEncoding()
for n in (3000, 40000):
    deck = np.argsort(rng.random((n, 52)), axis=1)[:, :7]
    shown = rng.choice([0, 3, 4, 5], n, p=[0.4, 0.3, 0.2, 0.1])
    for k in range(5): deck[shown <= k, 2 + k] = -1
    st = RawStates(cards=deck, raise_nums=rng.integers(0, 3, (n, 4)), legal_mask=rng.random((n, 4)) < 0.7)
    enc.encode(st)
    t = min(timeit.repeat(lambda: (Q.forget_recent_states(), enc.encode(st)), number=3, repeat=7)) / 3
    print(f"{n} states: {t*1e3:.1f} ms")
rec = pickle.load(open("states.pkl", "rb"))
big = RawStates(cards=np.concatenate([s.cards for s in rec]), raise_nums=np.concatenate([s.raise_nums for s in rec]), legal_mask=np.concatenate([s.legal_mask for s in rec]))
t = min(timeit.repeat(lambda: (Q.forget_recent_states(), enc.encode(big)), number=3, repeat=7)) / 3
print(f"the recorded 38,710 in one call: {t*1e3:.1f} ms")
