"""pokerirl: learn reward functions from real poker play.

IRC Poker Database ingest, AIRL / Hybrid-AIRL reward learning, DQN agents and tournaments,
all in RLCard's heads-up limit hold'em encoding.
"""

from __future__ import annotations

__version__ = "0.1.0"
