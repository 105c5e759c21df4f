"""Lock-step RL: R runs of one algorithm advancing together in one process (issue 19)."""

from __future__ import annotations

from pokerirl.gym.lockstep.dqn import LockstepDQN
from pokerirl.gym.lockstep.ppo import GroupResult, LockstepPPO, sb3_state_dict

__all__ = ["GroupResult", "LockstepDQN", "LockstepPPO", "sb3_state_dict"]
