"""The generic serializer: every type it reads and writes, the field metadata, and errors that
name the path of the bad value."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any, Literal

import pytest

from pokerirl.errors import InputError, PokerIRLError
from pokerirl.meanstd import Curve, MeanStd
from pokerirl.serial import Omit, SerialError, Serializable, from_json, meta, to_json


class Kind(StrEnum):
    SPARSE = "sparse"
    DENSE = "dense"


@dataclass(frozen=True, kw_only=True)
class Inner(Serializable):
    value: float
    note: str | None = field(default=None, metadata=meta(omit=Omit.NONE))


@dataclass(frozen=True, kw_only=True)
class Plain:  # a dataclass without the mixin: the functions read and write it too
    n: int


@dataclass(frozen=True, kw_only=True)
class Replaced(Serializable):
    replaced_by: str


@dataclass(frozen=True, kw_only=True)
class Outer(Serializable):
    kind: Kind
    name: str = field(metadata=meta(key="label"))
    pair: tuple[int, str]
    values: tuple[float, ...]
    items: list[Inner]
    by_kind: Mapping[Kind, Inner]
    by_int: dict[int, float]
    either: Inner | Replaced
    plain: Plain
    mode: Literal["a", "b"] = "a"
    path: Path = Path("x")
    hands: int = field(default=0, metadata=meta(omit=Omit.DEFAULT))
    cache: str = field(default="", metadata=meta(skip=True))
    settings: Mapping[str, Any] = field(default_factory=dict)
    maybe: list[int] | None = None


def outer() -> Outer:
    return Outer(
        kind=Kind.DENSE,
        name="n",
        pair=(1, "b"),
        values=(1.0, 2),
        items=[Inner(value=1.5), Inner(value=2.0, note="x")],
        by_kind={Kind.SPARSE: Inner(value=0.5)},
        by_int={3: 1.0},
        either=Replaced(replaced_by="r"),
        plain=Plain(n=4),
        path=Path("a/b"),
        cache="not written",
        settings={"free": [1, {"x": None}]},
    )


def test_writes_fields_in_order_with_keys_omissions_and_lists() -> None:
    assert outer().to_json() == {
        "kind": "dense",
        "label": "n",
        "pair": [1, "b"],
        "values": [1.0, 2],
        "items": [{"value": 1.5}, {"value": 2.0, "note": "x"}],
        "by_kind": {"sparse": {"value": 0.5}},
        "by_int": {"3": 1.0},
        "either": {"replaced_by": "r"},
        "plain": {"n": 4},
        "mode": "a",
        "path": "a/b",
        "settings": {"free": [1, {"x": None}]},
        "maybe": None,
    }
    assert list(outer().to_json()) == [
        "kind", "label", "pair", "values", "items", "by_kind", "by_int", "either", "plain",
        "mode", "path", "settings", "maybe",
    ]  # fmt: skip
    assert Outer.from_json(outer().to_json()) == Outer(**{**outer().__dict__, "cache": ""})


def test_round_trip_keeps_the_bytes() -> None:
    written = Outer(**{**outer().__dict__, "hands": 7}).to_json()  # not its default: written
    assert list(written)[11] == "hands"
    text = json.dumps(written, indent=2)
    assert json.dumps(Outer.from_json(json.loads(text)).to_json(), indent=2) == text


def test_reads_types_back() -> None:
    read = Outer.from_json({**outer().to_json(), "either": {"value": 1}, "maybe": [2]})
    assert read.kind is Kind.DENSE
    assert read.pair == (1, "b") and read.values == (1.0, 2)
    assert read.by_kind == {Kind.SPARSE: Inner(value=0.5)}
    assert read.by_int == {3: 1.0}
    assert read.either == Inner(value=1)
    assert read.plain == Plain(n=4) and read.path == Path("a/b") and read.maybe == [2]


def test_a_missing_key_reads_as_its_default_and_an_unknown_one_is_ignored() -> None:
    data = {k: v for k, v in outer().to_json().items() if k not in ("mode", "maybe")}
    read = Outer.from_json({**data, "added_later": 1})
    assert read.mode == "a" and read.maybe is None


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"items": [{"value": 1}, {"value": "x"}]}, "o.items[1].value: expected a number, got 'x'"),
        ({"kind": "other"}, "o.kind: expected one of 'sparse', 'dense', got 'other'"),
        ({"pair": [1]}, "o.pair: expected a list of 2, got [1]"),
        ({"pair": [1, 2]}, "o.pair[1]: expected a string, got 2"),
        ({"by_kind": {"sparse": {"value": True}}}, "o.by_kind.sparse.value: expected a number"),
        ({"by_int": {"a": 1.0}}, "o.by_int: expected integer keys, got 'a'"),
        ({"mode": "c"}, "o.mode: expected one of 'a', 'b', got 'c'"),
        ({"plain": {"n": 1.5}}, "o.plain.n: expected an integer, got 1.5"),
        ({"items": {}}, "o.items: expected a list, got {}"),
        ({"either": {"x": 1}}, "o.either: fits none of Inner or Replaced"),
        ({"label": None}, "o.label: expected a string, got None"),
    ],
)
def test_errors_name_the_path_of_the_bad_value(change: dict[str, Any], message: str) -> None:
    with pytest.raises(SerialError) as error:
        Outer.from_json({**outer().to_json(), **change}, path="o")
    assert str(error.value).startswith(message)
    assert "\n" not in str(error.value)
    assert isinstance(error.value, InputError) and isinstance(error.value, PokerIRLError)


def test_a_missing_required_key_is_named() -> None:
    data = {k: v for k, v in outer().to_json().items() if k != "label"}
    with pytest.raises(SerialError, match=r"^label: missing$"):
        Outer.from_json(data)
    with pytest.raises(SerialError, match=r"^the value: expected an object \(Inner\)"):
        from_json(Inner, [1])


@dataclass(frozen=True, kw_only=True)
class Line(Serializable):
    mbb: float
    n: int


@dataclass(frozen=True, kw_only=True)
class Row(Serializable):
    line: Line = field(metadata=meta(flatten=True))
    paper: float


@dataclass(frozen=True, kw_only=True)
class Kinds(Serializable):
    kinds: Mapping[str, Line] = field(metadata=meta(flatten=True))
    runs: int


def test_flatten_merges_a_dataclass_or_the_unclaimed_keys_into_the_parent() -> None:
    row = Row(line=Line(mbb=1.5, n=2), paper=3.0)
    assert row.to_json() == {"mbb": 1.5, "n": 2, "paper": 3.0}
    assert Row.from_json(row.to_json()) == row
    kinds = Kinds(kinds={"a": Line(mbb=1.0, n=1), "b": Line(mbb=2.0, n=2)}, runs=3)
    assert list(kinds.to_json()) == ["a", "b", "runs"]
    assert Kinds.from_json(kinds.to_json()) == kinds


@dataclass(frozen=True, kw_only=True)
class Derived(Serializable):
    seeds: tuple[int, ...]

    def to_json(self) -> dict[str, Any]:  # a derived key, before the fields
        return {"runs": len(self.seeds), **super().to_json()}


@dataclass(frozen=True, kw_only=True)
class HoldsDerived(Serializable):
    derived: Derived


def test_a_class_may_extend_the_generic_methods_and_nested_uses_them() -> None:
    held = HoldsDerived(derived=Derived(seeds=(1, 2)))
    assert to_json(held) == {"derived": {"runs": 2, "seeds": [1, 2]}}
    assert HoldsDerived.from_json(to_json(held)) == held


def test_meanstd_and_curve() -> None:
    assert MeanStd.from_json({"mean": 1.0}) == MeanStd(mean=1.0, std=None)
    assert MeanStd(mean=1.0, std=0.5).to_json() == {"mean": 1.0, "std": 0.5}
    with pytest.raises(SerialError, match=r"^final: expected an object"):
        MeanStd.from_json(3.0, path="final")
    curve = Curve.of([[1.0, 2.0], [3.0, 4.0]])
    assert curve.to_json() == {"mean": [2.0, 3.0], "std": [2.0**0.5, 2.0**0.5]}
    band = Curve(timesteps=[5, 10], mean=[1.0, 2.0], std=[0.0, 0.0])
    assert list(band.to_json()) == ["timesteps", "mean", "std"]
    assert Curve.from_json(band.to_json()) == band
