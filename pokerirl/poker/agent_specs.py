"""The spec prefixes of the agents made of an IRL run (:mod:`pokerirl.poker.run_agents`), apart
so that naming one needs no torch."""

REWARD_PREFIX = "reward:"  # reward:RUN or reward:authors:FILE: the reward's argmax
POLICY_PREFIX = "policy:"  # policy:RUN: the run's policy, greedy
