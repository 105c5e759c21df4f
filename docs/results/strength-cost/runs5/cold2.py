"""After 7 gradient updates of a small MLP (a DQN step), how long do the first small numpy
operations take, against the same with something else before them."""
import time, numpy as np, torch, sys
torch.set_num_threads(1)
net = torch.nn.Sequential(torch.nn.Linear(174, 64), torch.nn.Tanh(), torch.nn.Linear(64, 64), torch.nn.Tanh(), torch.nn.Linear(64, 4))
opt = torch.optim.Adam(net.parameters())
x = torch.randn(32, 174)
a = np.arange(50); b = np.arange(50) % 7
def step(): return ((a + b) * 3 > 10).sum()
def py(): return sum(i * 3 for i in range(50))
def full():
    for _ in range(7):
        opt.zero_grad(); net(x).pow(2).mean().backward(); opt.step()
def fwd():
    with torch.no_grad():
        for _ in range(7): net(x)
def mm():
    for _ in range(7): torch.mm(x, x.T)
def small():
    for _ in range(7): (x + 1).sum()
def sleep(): time.sleep(0.0005)
big = np.ones(4 << 20)
def npbig(): big.sum()
for name, before in (("full update", full), ("forward only", fwd), ("torch.mm", mm), ("small torch ops", small), ("sleep 0.5ms", sleep), ("numpy 32MB sum", npbig)):
    first = second = pyt = 0.0
    for _ in range(300):
        before()
        t = time.perf_counter(); py(); pyt += time.perf_counter() - t
        t = time.perf_counter(); step(); first += time.perf_counter() - t
        t = time.perf_counter(); step(); second += time.perf_counter() - t
    print(f"{name:18s} python first {pyt/300*1e6:6.1f} us, numpy first {first/300*1e6:6.1f} us, second {second/300*1e6:5.1f} us")
