"""How many cases each street's exact equity count is out of: the denominators that
:mod:`pokerirl.game.equity` (flop, turn, river) and :mod:`pokerirl.game.preflop` (the 169
classes) share. A count is ``2 x wins + ties`` over every runout and opponent hand.

>>> PREFLOP_DENOMINATOR == PREFLOP_FLOPS * FLOP_RUNOUTS * 2 * RIVER_OPPONENTS
True
"""

from __future__ import annotations

RIVER_OPPONENTS = 990  # two of the 45 cards neither the hand nor the board holds
TURN_RIVERS = 46
FLOP_RUNOUTS = 1_081  # turn and river from the 47 unseen cards
PREFLOP_FLOPS = 19_600  # three of the 50 cards
RIVER_DENOMINATOR = 2 * RIVER_OPPONENTS
TURN_DENOMINATOR = TURN_RIVERS * RIVER_DENOMINATOR
FLOP_DENOMINATOR = FLOP_RUNOUTS * RIVER_DENOMINATOR
PREFLOP_DENOMINATOR = PREFLOP_FLOPS * FLOP_DENOMINATOR
