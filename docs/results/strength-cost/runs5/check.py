"""Digest of the strength encoding (and version 1, and features) on recorded DQN calls + random batches; replay time."""
import pickle, hashlib, time, sys, numpy as np
import pokerirl.game.encodings as E, pokerirl.game.equity as Q
from pokerirl.game.encodings import RawStates
Q.use_turn_table(len(sys.argv) < 2 or sys.argv[1] != "count")
rec = pickle.load(open("states.pkl", "rb"))
enc = E.StrengthEncoding()
h = hashlib.sha256()
for s in rec: h.update(enc.encode(s).tobytes())
# merged big batches (LBR-like many rows) and random full states
rng = np.random.default_rng(5)
n = 3000
deck = np.argsort(rng.random((n, 52)), axis=1)[:, :7]
shown = rng.choice([0, 3, 4, 5], n)
cards = deck.copy()
for k in range(5): cards[shown <= k, 2 + k] = -1
raises = rng.integers(0, 3, (n, 4)); legal = rng.random((n, 4)) < 0.7
big = RawStates(cards=cards, raise_nums=raises, legal_mask=legal)
h.update(enc.encode(big).tobytes())
for size in (1, 2, 7, 40):
    for i in range(0, 400, size):
        h.update(enc.encode(big.take(np.arange(i, i + size))).tobytes())
# range rows: many pairs of one state
from pokerirl.holdem import PAIRS
st = big.take(np.arange(0, 8))
of = np.repeat(np.arange(8), 200); pairs = rng.integers(0, 1326, of.size)
h.update(enc.encode_pairs(pairs, st, of).tobytes())
print(h.hexdigest()[:16])
for _ in range(3):
    Q.forget_recent_states(); t = time.process_time()
    for s in rec: enc.encode(s)
    print("replay", round(time.process_time() - t, 4))
