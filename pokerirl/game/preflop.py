"""Preflop equity against a random hand, for the 169 classes of hole cards.

A class is a pocket pair, or two ranks suited or offsuit; every hand of a class has the same
equity against a uniformly random opponent hand and board. Two tables, 13 x 13 (row = higher
rank for suited hands and lower rank for offsuit ones, pairs on the diagonal; ranks 2 .. A as
0 .. 12):

* :data:`PREFLOP_COUNTS`, exact: ``2 x wins + ties`` of a hand of the class over every flop,
  turn, river and opponent hand (19,600 x 1,081 x 990 cases, :data:`PREFLOP_DENOMINATOR`),
  summed from the exact flop table by ``benchmarks/equity_tables.py``
  (:func:`pokerirl.game.equity.preflop_counts`); ``tests/test_equity.py`` sums it again and
  checks the published AA 85.2% and 72o 34.6%;
* :data:`PREFLOP_EQUITY`, the strength encoding's version 1 (kept for runs made with it):
  :func:`compute_preflop_table` with 200,000 runouts per class (seed 0; standard error about
  0.001).

>>> from pokerirl.holdem import parse_card
>>> aces, seven_deuce = [parse_card("As"), parse_card("Ah")], [parse_card("7c"), parse_card("2d")]
>>> [round(float(e), 3) for e in preflop_equity(np.array([aces, seven_deuce]))]
[0.852, 0.346]
"""

from __future__ import annotations

import numpy as np

from pokerirl.game.cases import PREFLOP_DENOMINATOR
from pokerirl.game.evaluator import _RANK, _SUIT, hand_strength
from pokerirl.holdem import NUM_CARDS

NUM_RANKS = 13


def _class_of(hole: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rank = _RANK[hole]  # 2 .. A as 0 .. 12
    high, low = rank.max(axis=1), rank.min(axis=1)
    suited = _SUIT[hole[:, 0]] == _SUIT[hole[:, 1]]
    return np.where(suited, high, low), np.where(suited, low, high)


# The class of every two cards, looked up (local best response asks for ~1,000 pairs of a
# range at each decision).
_ROW, _COLUMN = (
    found.reshape(NUM_CARDS, NUM_CARDS)
    for found in _class_of(np.indices((NUM_CARDS, NUM_CARDS)).reshape(2, -1).T)
)


def class_index(hole: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(row, column) of each hand's class in the 13 x 13 table."""
    hole = np.asarray(hole, dtype=np.int64)
    return _ROW[hole[:, 0], hole[:, 1]], _COLUMN[hole[:, 0], hole[:, 1]]


def sampled_preflop_equity(hole: np.ndarray) -> np.ndarray:
    """(N,) version 1's equity of (N, 2) hole cards: the 200,000-runout Monte Carlo table."""
    row, column = class_index(hole)
    return PREFLOP_EQUITY[row, column]


def preflop_equity(hole: np.ndarray) -> np.ndarray:
    """(N,) exact equity of (N, 2) hole cards against a random hand, from the shipped
    exact table (:data:`PREFLOP_COUNTS`)."""
    row, column = class_index(hole)
    return PREFLOP_COUNTS[row, column] / PREFLOP_DENOMINATOR


def compute_preflop_table(*, samples: int, seed: int = 0) -> np.ndarray:
    """(13, 13) Monte Carlo equity of each class: ``samples`` random opponent hands and
    boards for one hand of the class (suits do not matter preflop)."""
    rng = np.random.default_rng(seed)
    table = np.zeros((NUM_RANKS, NUM_RANKS))
    for row in range(NUM_RANKS):
        for column in range(NUM_RANKS):
            high, low = max(row, column), min(row, column)
            suited = row > column
            # Card index of rank r (2 .. A as 0 .. 12) in suit s: s * 13 + (r + 1) % 13.
            first = (high + 1) % NUM_RANKS
            second = (0 if suited else 1) * NUM_RANKS + (low + 1) % NUM_RANKS
            rest = np.setdiff1d(np.arange(NUM_CARDS), [first, second])
            keys = rng.random((samples, rest.size))
            chosen = np.argpartition(keys, 7, axis=1)[:, :7]
            # Shuffle the seven by their keys: argpartition's own order is not random.
            chosen = np.take_along_axis(
                chosen, np.take_along_axis(keys, chosen, 1).argsort(1), axis=1
            )
            drawn = rest[chosen]
            mine = np.concatenate([np.tile([first, second], (samples, 1)), drawn[:, 2:]], 1)
            ours, theirs = hand_strength(mine), hand_strength(drawn)
            table[row, column] = ((ours > theirs) + 0.5 * (ours == theirs)).mean()
    return table


# fmt: off
PREFLOP_EQUITY = np.array([
    [0.5025, 0.3240, 0.3320, 0.3433, 0.3424, 0.3447, 0.3663,
     0.3911, 0.4165, 0.4433, 0.4732, 0.5043, 0.5489],
    [0.3599, 0.5375, 0.3522, 0.3624, 0.3609, 0.3666, 0.3753,
     0.3997, 0.4253, 0.4530, 0.4830, 0.5137, 0.5571],
    [0.3679, 0.3875, 0.5702, 0.3803, 0.3790, 0.3886, 0.3939,
     0.4044, 0.4336, 0.4628, 0.4920, 0.5247, 0.5688],
    [0.3770, 0.3981, 0.4167, 0.6029, 0.3996, 0.4061, 0.4149,
     0.4241, 0.4419, 0.4732, 0.5030, 0.5327, 0.5771],
    [0.3784, 0.3935, 0.4128, 0.4328, 0.6337, 0.4215, 0.4319,
     0.4465, 0.4600, 0.4781, 0.5094, 0.5413, 0.5764],
    [0.3814, 0.4007, 0.4185, 0.4364, 0.4541, 0.6629, 0.4503,
     0.4624, 0.4794, 0.4974, 0.5187, 0.5511, 0.5886],
    [0.4039, 0.4096, 0.4264, 0.4461, 0.4615, 0.4811, 0.6925,
     0.4797, 0.4989, 0.5151, 0.5373, 0.5606, 0.6000],
    [0.4258, 0.4331, 0.4391, 0.4605, 0.4742, 0.4917, 0.5077,
     0.7190, 0.5148, 0.5325, 0.5549, 0.5801, 0.6073],
    [0.4480, 0.4576, 0.4665, 0.4738, 0.4897, 0.5061, 0.5230,
     0.5407, 0.7508, 0.5522, 0.5743, 0.5979, 0.6262],
    [0.4718, 0.4822, 0.4917, 0.5009, 0.5071, 0.5232, 0.5391,
     0.5552, 0.5743, 0.7740, 0.5797, 0.6058, 0.6363],
    [0.5035, 0.5119, 0.5180, 0.5293, 0.5365, 0.5433, 0.5610,
     0.5759, 0.5957, 0.6017, 0.7985, 0.6165, 0.6419],
    [0.5314, 0.5397, 0.5474, 0.5572, 0.5658, 0.5749, 0.5828,
     0.6008, 0.6188, 0.6263, 0.6355, 0.8252, 0.6523],
    [0.5717, 0.5833, 0.5884, 0.5983, 0.5984, 0.6097, 0.6185,
     0.6271, 0.6445, 0.6557, 0.6611, 0.6723, 0.8534],
])
# fmt: on

# Made by benchmarks/equity_tables.py from the exact flop table (see the module docstring).
# fmt: off
PREFLOP_COUNTS = np.array([
    [21115849840, 13551671950, 13927775910, 14382905230, 14295013940, 14508340820,
     15449742550, 16402150410, 17480476430, 18604824330, 19841120610, 21189140990,
     23043325730],
    [15095989690, 22525023020, 14744211190, 15213596600, 15135088590, 15355176810,
     15725002150, 16788765750, 17869030850, 18993746670, 20228751630, 21573821450,
     23427619310],
    [15450304960, 16210856880, 23921899180, 16006695420, 15945950210, 16172210980,
     16548500210, 17062095870, 18250603250, 19375857090, 20609774850, 21952132250,
     23798921210],
    [15878341150, 16651772480, 17390310090, 25307177660, 16757213210, 16995357550,
     17379447020, 17900323260, 18563914090, 19793065790, 21026100470, 22365983590,
     24204531610],
    [15802675890, 16584900840, 17339925840, 18095080090, 26548868240, 17755005150,
     18140184460, 18664763570, 19336262790, 20071365330, 21405328770, 22747450670,
     24198623980],
    [16006949810, 16795654820, 17556392310, 18322520040, 19034113090, 27786970660,
     18899468080, 19422600180, 20098156560, 20842290540, 21716446430, 23151892510,
     24684733500],
    [16894533780, 17147026820, 17913950970, 18687269450, 19399721060, 20109988850,
     29014894860, 20177401690, 20858794270, 21600868960, 22485888900, 23501273560,
     25117424790],
    [17793778770, 18149982610, 18400731880, 19180988430, 19896854740, 20605599420,
     21311652480, 30229060580, 21618282750, 22339648170, 23224504070, 24252939510,
     25495072270],
    [18810812280, 19168670420, 19520215830, 19807904330, 20531322110, 21243809500,
     21955026320, 22665330590, 31468527860, 23177211430, 24034312870, 25061339920,
     26312642330],
    [19875820970, 20233864670, 20585765740, 20970207180, 21229910820, 21951003370,
     22660344880, 23351212390, 24133769060, 32499565640, 24388344110, 25409440460,
     26665707090],
    [21046636740, 21403312660, 21754050070, 22137531970, 22491247930, 22780585710,
     23500250120, 24191017940, 24947502220, 25279609110, 33529763640, 25781598000,
     27030089590],
    [22323090540, 22676845340, 23024899770, 23405936830, 23761608710, 24137914030,
     24462875160, 25166034110, 25921194850, 26247905160, 26597387220, 34566180760,
     27402715950],
    [24071278500, 24424267520, 24765465100, 25138534980, 25131362300, 25583653660,
     25986325510, 26337628310, 27101636700, 27433175740, 27775576480, 28126194060,
     35744191480],
], dtype=np.int64)
# fmt: on
