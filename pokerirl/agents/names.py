"""The names agent specs and agent folders are made of, apart and torch-free: the spec
prefix of an RLCard checkpoint and an agent folder's files.

Resolving a spec (:mod:`pokerirl.agents.registry`) lazily imports the loaders
(:mod:`pokerirl.agents.checkpoint`, :mod:`pokerirl.agents.rlcard_import`), which name these
too; held here, neither imports the other back, and shipping an agent needs no torch.
"""

from __future__ import annotations

RLCARD_PREFIX = "rlcard:"  # rlcard:PATH: the greedy policy of an RLCard DQNAgent checkpoint
MODEL_FILE, CONFIG_FILE, KEPT_FILE = "model.pt", "config.json", "kept.pt"
