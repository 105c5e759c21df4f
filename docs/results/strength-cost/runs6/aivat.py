import hashlib, time, numpy as np
from pokerirl.game import make_agent
from pokerirl.tournaments.aivat import play_corrected_match
from pokerirl.tournaments.equity import showdown_shares
h = hashlib.sha256()
for a, b in (("raise", "random"), ("tightbot", "call"), ("loosebot", "tightbot")):
    m = play_corrected_match(make_agent(a), make_agent(b), hands=20_000, seed=3)
    h.update(m.corrected_bb.tobytes())
rng = np.random.default_rng(4)
cards = rng.random((20000, 52)).argsort(axis=1)[:, :14]
h.update(showdown_shares(cards[:, :4].reshape(-1, 2, 2), cards[:, 4:].reshape(-1, 2, 5)).tobytes())
print("digest", h.hexdigest()[:16])
ts = []
for _ in range(3):
    t = time.perf_counter(); m = play_corrected_match(make_agent("raise"), make_agent("random"), hands=400_000, seed=7); ts.append((m.match.seconds, m.match.on_batch_seconds))
print("play s, aivat s (best of 3):", min(t[0] for t in ts), min(t[1] for t in ts))
