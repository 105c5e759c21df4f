"""Records the strength encoding's calls of a 20,000-hand DQN run (seed 0, own play, turn table
on) into states.pkl (not kept: 324 calls, rebuilt in ~3 s)."""
import os, pickle, copy
os.environ["OMP_NUM_THREADS"] = "1"
import torch; torch.set_num_threads(1)
import pokerirl.agents.dqn as D
import pokerirl.game.encodings as E
from pokerirl.game import make_agent
from pokerirl.game.equity import use_turn_table
use_turn_table(True)
rec = []
orig = E.StrengthEncoding.encode
def enc(self, states):
    rec.append(copy.deepcopy(states)); return orig(self, states)
E.StrengthEncoding.encode = enc
D.train_dqn(D.DQNConfig(), hands=20000, seed=0, opponent=make_agent("random"), encoding="strength")
pickle.dump(rec, open("states.pkl", "wb"))
print(len(rec), sum(len(s.cards) for s in rec))
