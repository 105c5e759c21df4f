import os
os.environ["OMP_NUM_THREADS"]="1"
import statistics
from pokerirl.game import make_agent, play_match
r, a = make_agent("random"), make_agent("raise")
play_match(r, r, hands=10000, seed=0)
s = [play_match(a, r, hands=400000, seed=0, duplicate=False).seconds for _ in range(7)]
print(f"min {min(s)*1000:.1f} ms median {statistics.median(s)*1000:.1f} ms")
