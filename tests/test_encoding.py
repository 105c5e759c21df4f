from __future__ import annotations

import json
import os

import numpy as np
import rlcard
from hypothesis import given
from hypothesis import strategies as st
from rlcard.envs.limitholdem import LimitholdemEnv

from pokerirl.holdem import (
    ACTIONS,
    OBS_SIZE,
    card_str,
    encode_obs,
    parse_card,
    rlcard_card_str,
)


def test_card_order_matches_rlcard_card2index() -> None:
    path = os.path.join(rlcard.__path__[0], "games/limitholdem/card2index.json")
    with open(path) as handle:
        card2index = json.load(handle)
    for index in range(52):
        assert card2index[rlcard_card_str(index)] == index
        assert parse_card(card_str(index)) == index


def test_actions_match_rlcard_env() -> None:
    env = rlcard.make("limit-holdem")
    assert isinstance(env, LimitholdemEnv)
    assert tuple(env.actions) == ACTIONS
    assert env.state_shape[0] == [OBS_SIZE]


@given(
    cards=st.lists(st.integers(0, 51), min_size=2, max_size=7, unique=True),
    raise_nums=st.lists(st.integers(0, 4), min_size=4, max_size=4),
)
def test_encode_obs_matches_rlcard_extract_state(cards: list[int], raise_nums: list[int]) -> None:
    env = rlcard.make("limit-holdem")
    state = {
        "hand": [rlcard_card_str(c) for c in cards[:2]],
        "public_cards": [rlcard_card_str(c) for c in cards[2:]],
        "raise_nums": raise_nums,
        "legal_actions": ["call", "raise", "fold"],
    }
    expected = env._extract_state(state)["obs"]
    padded = np.full((1, 7), -1)
    padded[0, : len(cards)] = cards
    ours = encode_obs(padded, np.array([raise_nums]))
    assert ours.dtype == np.uint8
    np.testing.assert_array_equal(ours[0], expected)


def test_parse_card_rejects_garbage() -> None:
    for bad in ["", "X", "1c", "Qx", "Qcc"]:
        try:
            parse_card(bad)
        except ValueError:
            continue
        raise AssertionError(f"{bad!r} was accepted")
