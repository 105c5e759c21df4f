"""The paper's Gymnasium half: task presets, SB3 experts, expert data, the IRL phase
(:mod:`pokerirl.gym.irl`) and the RL phase.

Gymnasium and Stable-Baselines3 (the ``pokerirl[gym]`` extra) are imported lazily, inside the
functions that need them, so importing :mod:`pokerirl.gym.presets` costs a poker-only user
nothing.
"""
