"""The authors' published poker rewards (``authors:FILE``), read without unpickling.

The authors (silue-dev/hairl) saved each trained reward with ``torch.save`` of their whole
``Discriminator`` module: a zip whose ``data.pkl`` is a pickle (which could run code) and
whose ``data/<k>`` members hold the tensors raw, little-endian float32. We read only the
raw members, with :mod:`zipfile` and :func:`numpy.frombuffer`, after checking the layout:

* ``data/0``: ``layers.0.weight`` (64, 65); ``data/1``: ``layers.0.bias`` (64);
  ``data/2``: ``output_layer.weight`` (1, 64); ``data/3``: ``output_layer.bias`` (1);
* ``data.pkl`` is parsed, never run (:func:`pickletools.genops` only lists its opcodes), to
  check that it is a ``Discriminator`` whose four storages are those, in that order;
* anything else (other members, sizes, byte order, class) is refused in one line.

The forward pass is theirs: ``f = W2 · leaky_relu(W1 · x + b1, 0.01) + b2``, with ``x`` their
61-d state followed by a one-hot of the action in RLCard's order (call, raise, fold, check).
Their state (``src/envs/poker/data/preprocessing.py``, ``get_state_vector``): the hole cards
then the board, in the order dealt, each card as 4 bits of rank (2 -> 1 ... A -> 13) then 3
bits of suit (S 1, H 2, D 3, C 4), most significant bit first, zero-padded to 49 bits; then
each round's raise count as 3 bits. Both of their card formats ('rs' for the IRC data, 'sr'
for RLCard's cards) only change how a card's text is parsed: the rank bits always come first
(``cards_vector += rank_binary + suit_binary``).

>>> cards = np.array([[0, 51, -1, -1, -1, -1, -1]])  # As, Kc
>>> authors_state(cards, np.zeros((1, 4), int))[0, :14].astype(int).tolist()
[1, 1, 0, 1, 0, 0, 1, 1, 1, 0, 0, 1, 0, 0]
"""

from __future__ import annotations

import hashlib
import os
import pickletools
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pokerirl.errors import InputError
from pokerirl.holdem import NUM_ACTIONS
from pokerirl.poker.rewards import AUTHORS_PREFIX, ObservedDecisions, PokerReward, read_capped

STATE_SIZE = 61  # 7 cards x 7 bits, then 4 rounds x 3 bits
HIDDEN = 64
# Member -> (parameter, shape), in the order torch.save numbers the storages.
TENSORS = {
    "data/0": ("layers.0.weight", (HIDDEN, STATE_SIZE + NUM_ACTIONS)),
    "data/1": ("layers.0.bias", (HIDDEN,)),
    "data/2": ("output_layer.weight", (1, HIDDEN)),
    "data/3": ("output_layer.bias", (1,)),
}
# Other members torch.save writes (which depend on its version); none carry weights.
OPTIONAL_MEMBERS = (
    "version",
    "byteorder",
    ".format_version",
    ".storage_alignment",
    ".data/version",
    ".data/serialization_id",
)
LEAKY_SLOPE = 0.01  # torch.nn.functional.leaky_relu's default, which their forward uses
_RANK_BITS, _SUIT_BITS, _RAISE_BITS = 4, 3, 3


class AuthorsFileError(InputError):
    """A file that is not one of the authors' poker rewards, in one line naming it."""


@dataclass(frozen=True, kw_only=True)
class AuthorsWeights:
    """The four tensors of an authors' reward and the sha256 of its file."""

    w1: np.ndarray = field(repr=False)  # (64, 65)
    b1: np.ndarray = field(repr=False)  # (64,)
    w2: np.ndarray = field(repr=False)  # (1, 64)
    b2: np.ndarray = field(repr=False)  # (1,)
    fingerprint: str


def _storages(pickle_bytes: bytes) -> list[tuple[str, int, str]]:
    """(storage key, element count, pickled class name) of each storage, in order, from
    ``data.pkl``'s opcodes (parsed, never executed)."""
    memo: dict[int, object] = {}
    recent: list[object] = []  # the values the last opcodes pushed
    found: list[tuple[str, int, str]] = []
    class_name = ""
    for opcode, argument, _ in pickletools.genops(pickle_bytes):
        name = opcode.name
        if name in ("BINPUT", "LONG_BINPUT", "PUT"):
            if recent:
                memo[int(argument)] = recent[-1]  # type: ignore[arg-type]
            continue
        if name == "MEMOIZE":
            if recent:
                memo[len(memo)] = recent[-1]
            continue
        if name in ("BINGET", "LONG_BINGET", "GET"):
            recent.append(memo.get(int(argument)))  # type: ignore[arg-type]
        elif name in ("GLOBAL", "STACK_GLOBAL"):
            if name == "STACK_GLOBAL":  # protocol 4: module and name were pushed as strings
                argument = f"{recent[-2]} {recent[-1]}"
                del recent[-2:]
            recent.append(argument)
            if not class_name:
                class_name = str(argument).split(" ")[-1]
        elif name == "BINPERSID":
            # ('storage', <storage class>, key, location, numel) was just pushed as a tuple.
            key, numel = recent[-4], recent[-2]
            found.append((str(key), int(numel), class_name))  # type: ignore[call-overload]
            recent.append(None)
        else:
            recent.append(argument)
        del recent[:-16]
    return found


# A real file is about 20 KB and its data.pkl under 2 KB: anything far larger is not one, and
# is refused before it is read or inflated (a 4 MB zip can declare a 4 GiB member).
MAX_FILE_BYTES = 1024 * 1024
MAX_MEMBER_BYTES = 256 * 1024


def read_authors_file(path: str | os.PathLike[str]) -> AuthorsWeights:
    """The weights of an authors' reward file; :class:`AuthorsFileError` for any other file."""
    path = Path(path)
    where = f"{AUTHORS_PREFIX}{path}"
    try:
        raw = read_capped(path, MAX_FILE_BYTES, where=where)
    except InputError as error:
        raise AuthorsFileError(str(error)) from None
    return read_authors_bytes(raw, where=where)


def _inflated(archive: zipfile.ZipFile, name: str, cap: int, where: str) -> bytes:
    """A member's bytes, inflating at most ``cap`` + 1 of them; a damaged member (bad CRC, a
    broken deflate stream, a truncated archive) is one line naming the file."""
    import zlib

    try:
        with archive.open(name) as member:
            data = member.read(cap + 1)
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError, ValueError) as error:
        raise AuthorsFileError(f"{where}: damaged zip member {name} ({error})") from None
    if len(data) > cap:
        raise AuthorsFileError(f"{where}: member {name} inflates beyond {cap:,} bytes")
    return data


def read_authors_bytes(raw: bytes, *, where: str) -> AuthorsWeights:
    """The weights in the bytes of an authors' reward file (``where`` names it in errors)."""
    if len(raw) > MAX_FILE_BYTES:
        raise AuthorsFileError(
            f"{where}: {len(raw):,} bytes, more than the {MAX_FILE_BYTES:,} such a file can hold"
        )
    try:
        import io

        archive = zipfile.ZipFile(io.BytesIO(raw))
        infos = {info.filename: info for info in archive.infolist()}
    except (zipfile.BadZipFile, OSError, ValueError, EOFError):
        raise AuthorsFileError(f"{where}: not a torch.save zip (an authors' reward)") from None
    prefixes = {name.split("/", 1)[0] for name in infos}
    if len(prefixes) != 1 or any("/" not in name for name in infos):
        raise AuthorsFileError(f"{where}: not a torch.save zip (members outside one folder)")
    prefix = prefixes.pop() + "/"
    members = {name.removeprefix(prefix): info for name, info in infos.items()}
    expected = {"data.pkl", *TENSORS}
    unknown = sorted(set(members) - expected - set(OPTIONAL_MEMBERS))
    missing = sorted(expected - set(members))
    if unknown or missing:
        detail = f"unexpected {unknown[0]}" if unknown else f"no {missing[0]}"
        raise AuthorsFileError(
            f"{where}: not the authors' poker reward layout ({detail}; expected data.pkl and "
            "data/0..3 of a 65-64-1 Discriminator)"
        )
    for member, (parameter, shape) in TENSORS.items():
        size = 4 * int(np.prod(shape))
        if members[member].file_size != size:
            raise AuthorsFileError(
                f"{where}: {member} holds {members[member].file_size} bytes, not the "
                f"{size} of {parameter} {shape} in float32"
            )
    for member, info in members.items():
        if member not in TENSORS and info.file_size > MAX_MEMBER_BYTES:
            raise AuthorsFileError(
                f"{where}: member {member} declares {info.file_size:,} bytes, more than the "
                f"{MAX_MEMBER_BYTES:,} an authors' reward holds"
            )

    def read(member: str) -> bytes:
        size = members[member].file_size
        cap = size if member in TENSORS else MAX_MEMBER_BYTES
        return _inflated(archive, prefix + member, cap, where)

    if "byteorder" in members and read("byteorder").strip() != b"little":
        raise AuthorsFileError(f"{where}: tensors are not little-endian")
    try:
        storages = _storages(read("data.pkl"))
    except (ValueError, IndexError, TypeError, KeyError):
        raise AuthorsFileError(f"{where}: data.pkl is not a torch module pickle") from None
    wanted = [(m.removeprefix("data/"), int(np.prod(s))) for m, (_, s) in TENSORS.items()]
    if [(key, numel) for key, numel, _ in storages] != wanted or storages[0][2] != "Discriminator":
        raise AuthorsFileError(
            f"{where}: data.pkl is not the authors' Discriminator (its storages are "
            f"{[(key, numel) for key, numel, _ in storages]}, class "
            f"{storages[0][2] if storages else '?'!r})"
        )
    tensors = [
        np.frombuffer(read(member), dtype="<f4").reshape(shape).astype(np.float32)
        for member, (_, shape) in TENSORS.items()
    ]
    if not all(np.isfinite(t).all() for t in tensors):
        raise AuthorsFileError(f"{where}: weights hold NaN or infinity")
    return AuthorsWeights(
        w1=tensors[0],
        b1=tensors[1],
        w2=tensors[2],
        b2=tensors[3],
        fingerprint=f"sha256:{hashlib.sha256(raw).hexdigest()}",
    )


def _bits(values: np.ndarray, width: int) -> np.ndarray:
    """(..., width) most-significant-first binary digits of non-negative integers."""
    shifts = np.arange(width - 1, -1, -1)
    return (np.asarray(values, dtype=np.int64)[..., None] >> shifts) & 1


def authors_state(cards: np.ndarray, raises: np.ndarray) -> np.ndarray:
    """(N, 61) float32: the authors' state of cards (hole then board, -1 beyond) and raises.

    Rank is 2 -> 1 ... K -> 12, A -> 13 (ours is A, 2..K as 0..12 within a suit); suit is
    S 1, H 2, D 3, C 4 (ours 0..3 in that order).
    """
    cards = np.asarray(cards, dtype=np.int64)
    shown = cards >= 0
    rank = np.where(cards % 13 == 0, 13, cards % 13)
    suit = cards // 13 + 1
    per_card = np.concatenate([_bits(rank, _RANK_BITS), _bits(suit, _SUIT_BITS)], axis=2)
    per_card = np.where(shown[..., None], per_card, 0).reshape(len(cards), -1)
    raise_bits = _bits(np.minimum(np.asarray(raises), 7), _RAISE_BITS).reshape(len(cards), -1)
    return np.concatenate([per_card, raise_bits], axis=1).astype(np.float32)


class AuthorsReward(PokerReward):
    """An authors' published reward f(s, a) on our decisions (see the module docstring)."""

    needs_cards = True

    def __init__(self, weights: AuthorsWeights, *, name: str = "authors") -> None:
        self.weights, self.name, self.fingerprint = weights, name, weights.fingerprint

    @classmethod
    def from_file(cls, path: str | os.PathLike[str]) -> AuthorsReward:
        return cls(read_authors_file(path), name=f"{AUTHORS_PREFIX}{path}")

    def _hidden_parts(self, decisions: ObservedDecisions) -> tuple[np.ndarray, np.ndarray]:
        if decisions.cards is None:
            raise ValueError(
                "the authors' reward reads the cards: ObservedDecisions.cards is missing"
            )
        state = authors_state(decisions.cards, decisions.raise_counts())
        w1 = self.weights.w1
        return state @ w1[:, :STATE_SIZE].T + self.weights.b1, w1[:, STATE_SIZE:]

    def _head(self, pre: np.ndarray) -> np.ndarray:
        hidden = np.where(pre > 0, pre, LEAKY_SLOPE * pre)
        return (hidden @ self.weights.w2.T + self.weights.b2)[..., 0].astype(np.float32)

    def __call__(self, decisions: ObservedDecisions, actions: np.ndarray) -> np.ndarray:
        state_part, action_columns = self._hidden_parts(decisions)
        return self._head(state_part + action_columns.T[np.asarray(actions, dtype=np.int64)])

    def action_values(self, decisions: ObservedDecisions) -> np.ndarray:
        state_part, action_columns = self._hidden_parts(decisions)
        return self._head(state_part[:, None, :] + action_columns.T[None, :, :])
