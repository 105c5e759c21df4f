import hashlib, numpy as np
from pokerirl.game import make_agent, play_match
from pokerirl.game.deals import deal_cards
h = hashlib.sha256()
h.update(deal_cards(seed=3, start=100, count=300_000).tobytes())
names = ["random", "raise", "call", "tightbot", "loosebot", "fold"]
for i, a in enumerate(names):
    for b in names[i:]:
        for dup in (True, False):
            m = play_match(make_agent(a), make_agent(b), hands=20_000, seed=5, duplicate=dup, batch_size=4096)
            h.update(m.results_bb.tobytes())
log = []
m = play_match(make_agent("tightbot"), make_agent("random"), hands=5000, seed=2, log=log)
for part in log:
    for x in (part.obs, part.legal_mask, part.cards, part.actions):
        h.update(np.ascontiguousarray(x).tobytes())
print(h.hexdigest()[:16])
