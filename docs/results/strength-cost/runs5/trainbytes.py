"""Digests of DQN training (weights, replay memory) under several settings: the same bytes
before and after a change of the training loop's order of pure computations."""
import os, hashlib
os.environ["OMP_NUM_THREADS"] = "1"
import numpy as np, torch
torch.set_num_threads(1)
from pokerirl.agents.dqn import DQNConfig, train_dqn
from pokerirl.game import make_agent

def digest(learner):
    h = hashlib.sha256()
    for v in learner.q_net.state_dict().values(): h.update(v.numpy().tobytes())
    r = learner.replay
    for a in (r.obs, r.actions, r.rewards, r.next_obs, r.next_legal, r.done): h.update(np.ascontiguousarray(a).tobytes())
    h.update(str((learner.total_t, learner.train_t)).encode())
    return h.hexdigest()[:16]

def reward(obs, actions):  # a reward of the obs and action, deterministic
    return (obs[:, :8].astype(np.float32).sum(1) * 0.01 + actions * 0.1).astype(np.float32)

small = DQNConfig(concurrent_hands=128, replay_init=64)
cases = {
    "rlcard sparse vs random": dict(opponent=make_agent("random")),
    "strength sparse vs random": dict(opponent=make_agent("random"), encoding="strength"),
    "strength reward decision": dict(opponent=make_agent("raise"), encoding="strength", reward_fn=reward, payoff_weight=0.3),
    "rlcard reward end-of-hand": dict(opponent=make_agent("random"), reward_fn=reward, payoff_weight=0.5, raise_counts="end-of-hand"),
    "strength self-play": dict(opponent="self", encoding="strength"),
    "rlcard pool": dict(opponent="pool"),
}
for name, kw in cases.items():
    learner = train_dqn(small, hands=3000, seed=11, **kw)
    print(f"{name:28s} {digest(learner)}")
