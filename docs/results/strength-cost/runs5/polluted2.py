"""The recorded calls replayed after 7 gradient updates each (as in a run), the first numpy
operation after them absorbed by a trivial one (as legal_mask does in a run): encode alone,
whole (full), with the river counts stubbed (noriver), with no equity at all (noequity)."""
import pickle, time, numpy as np, sys
import pokerirl.game.encodings as E, pokerirl.game.equity as Q
Q.use_turn_table(True)
rec = pickle.load(open("states.pkl", "rb"))
enc = E.StrengthEncoding()
if "noriver" in sys.argv:
    Q._RIVER_ROWS.__class__.__call__ = lambda self, p, b: np.zeros(len(p), np.int64)
if "noequity" in sys.argv:
    E.range_equity = lambda p, b, of: np.zeros(len(p))
for s in rec[:20]: enc.encode(s)
import torch
torch.set_num_threads(1)
net = torch.nn.Sequential(torch.nn.Linear(174, 64), torch.nn.Tanh(), torch.nn.Linear(64, 64), torch.nn.Tanh(), torch.nn.Linear(64, 4))
opt = torch.optim.Adam(net.parameters())
x = torch.randn(32, 174)
a = np.arange(50)
ts = []
for _ in range(5):
    Q.forget_recent_states(); total = 0.0
    for s in rec:
        for _ in range(7):
            opt.zero_grad(); net(x).pow(2).mean().backward(); opt.step()
        (a + 1).sum()  # the first numpy op after the updates pays their cold start (as legal_mask does in a run)
        t = time.perf_counter(); enc.encode(s); total += time.perf_counter() - t
    ts.append(total)
print(sys.argv[1:], f"min {min(ts)*1e3:.1f} ms median {np.median(ts)*1e3:.1f}")
