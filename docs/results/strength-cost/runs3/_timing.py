"""What parts.py and parts2.py share: CPU seconds spent inside wrapped functions during
20,000-hand DQN runs (seed 0, own play, against random, one torch thread)."""
import os

os.environ["OMP_NUM_THREADS"] = "1"
import time

import torch

torch.set_num_threads(1)
import pokerirl.agents.dqn as D
from pokerirl.game import make_agent
from pokerirl.game.equity import forget_recent_states

acc: dict[str, float] = {}  # label -> CPU seconds inside it in the current run


def wrap(owner, name, label):
    """Replace ``owner.name`` by itself timed into ``acc[label]``."""
    orig = getattr(owner, name)

    def timed(*a, **k):
        t = time.process_time()
        r = orig(*a, **k)
        acc[label] = acc.get(label, 0) + time.process_time() - t
        return r

    setattr(owner, name, timed)


def runs(encodings):
    """For each encoding: a 1,000-hand warm-up (seed 1), then 20,000 hands of seed 0 timed
    from no remembered equity; yields (encoding, total CPU s, learner) with ``acc`` filled."""
    for enc in encodings:
        D.train_dqn(D.DQNConfig(), hands=1000, seed=1, opponent=make_agent("random"), encoding=enc)
        forget_recent_states()
        acc.clear()
        t = time.process_time()
        learner = D.train_dqn(D.DQNConfig(), hands=20000, seed=0, opponent=make_agent("random"),
                              encoding=enc)
        yield enc, time.process_time() - t, learner
