"""Lock-step RL: R runs of one algorithm advancing together in one process (issue 19)."""

from __future__ import annotations

from pokerirl.gym.lockstep.dqn import DQNGroupResult, LockstepDQN
from pokerirl.gym.lockstep.ppo import LockstepPPO, PPOGroupResult, sb3_state_dict

__all__ = ["DQNGroupResult", "LockstepDQN", "LockstepPPO", "PPOGroupResult", "sb3_state_dict"]
