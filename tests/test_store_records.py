"""Unit records: today's format round-trips, and the two formats written before the store
(``pokerirl-unit/1``, ``pokerirl-study-stage/1``) are recognised, refused in one line naming
the file, or recomputed when corrupt.

The ``*_V1`` texts below are byte for byte what ``execution.save_unit_folder``,
``execution.save_record`` and ``study.pipeline.Study.stage`` wrote at commit 561c0d2, so these
tests keep guarding old folders after round 2 deletes those functions.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from pokerirl.cli.errors import ADVICE
from pokerirl.errors import Remedy, report
from pokerirl.store import (
    Fate,
    Layout,
    LegacyRecord,
    Unit,
    UnitConflict,
    UnitRecord,
    check,
    digest,
    fingerprint,
    read_record,
)

# execution.save_unit_folder("run-1", {"reward.pt": b"weights"}, CONFIG_V1,
#                            unhashed={"timings.json": b"{}\n"})
CONFIG_V1 = {
    "algo": "hairl",
    "device": "cpu",
    "table": digest(b"rows"),
    "settings": {"epochs": 2, "seed": 1},
}
FOLDER_RECORD_V1 = """{
  "config": {
    "algo": "hairl",
    "device": "cpu",
    "settings": {
      "epochs": 2,
      "seed": 1
    },
    "table": "sha256:bc51e9e65d79e1c90ba544ab2eae1044ccdf8c1af7a559ba375cba4276f7d99e"
  },
  "files": {
    "reward.pt": "sha256:9a129038d9a00aed0cf6a7ea059ca50a813449061ab87848cf1a13eafdf33b2c"
  },
  "fingerprint": "sha256:c2b4139c01eb1feb39a395f6847c647d3bf10a8b76e575ea96a0788f36b8375b",
  "format": "pokerirl-unit/1",
  "result": null
}
"""
# execution.save_record("seed-0.json", make_record(SEED_CONFIG, result=...)): a tournament seed
SEED_CONFIG = {"kind": "pokerirl-tournament-seed", "seed": 0}
SEED_RECORD_V1 = """{
  "config": {
    "kind": "pokerirl-tournament-seed",
    "seed": 0
  },
  "files": {},
  "fingerprint": "sha256:183e0561a97e8c7a2040f7edd70c5fdd0d968bfe48b8678003e2bad71a9a893b",
  "format": "pokerirl-unit/1",
  "result": {
    "estimate": {
      "mbb_per_hand": 1.5
    }
  }
}
"""
# gym/jobs.py's expert data: expert.parquet and expert.unit.json beside it
DATA_CONFIG = {"unit": "gym-data", "seed": 0}
DATA_RECORD_V1 = """{
  "config": {
    "seed": 0,
    "unit": "gym-data"
  },
  "files": {
    "expert.parquet": "sha256:0d4fc4a78d3706edccafb665a8b2fdd9309e82c78625bb0f2b8e7bb9e1c4d21c"
  },
  "fingerprint": "sha256:ddd701a0813c072cfe3d6f15e27210b6b92643334cdeb84c93116ee8d3c21a51",
  "format": "pokerirl-unit/1",
  "result": null
}
"""
# study.pipeline.Study.stage("ingest", INGEST_SETTINGS, ...) -> stages/ingest.json
INGEST_SETTINGS = {"sources": {"files": [["/data/199504/hroster", 10, 1]]}}
STAGE_RECORD_V1 = """{
 "format": "pokerirl-study-stage/1",
 "stage": "ingest",
 "fingerprint": "sha256:c3c3a51c703f67a9f65c6d1ef5e8c0515001f7e1b5b1e0a1456a18ab1601407c",
 "settings": {
  "sources": {
   "files": [
    [
     "/data/199504/hroster",
     10,
     1
    ]
   ]
  }
 },
 "finished": true,
 "result": {
  "summary": {
   "rows": 10
  }
 }
}
"""


def old_run_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "runs" / "run-1"
    folder.mkdir(parents=True)
    (folder / "reward.pt").write_bytes(b"weights")
    (folder / "timings.json").write_text("{}\n")
    (folder / "unit.json").write_text(FOLDER_RECORD_V1)
    return folder


def run_unit(folder: Path, **settings: int) -> Unit[None]:
    """The unit of ``old_run_folder`` as round 2 declares it: the table's digest as an input."""
    config = {k: v for k, v in CONFIG_V1.items() if k != "table"}
    config["settings"] = {**CONFIG_V1["settings"], **settings}  # type: ignore[dict-item]
    return Unit(key=folder.name, target=folder, config=config, inputs={"table": digest(b"rows")})


def test_the_record_written_round_trips_and_keeps_its_fingerprint() -> None:
    record = UnitRecord.make(
        {"seed": (1, 2)}, inputs={"data": digest(b"x")}, files={"a/b.pt": b"w"}, result=[1]
    )
    assert record.config == {"seed": [1, 2]}  # plain JSON: tuples are lists
    assert record.fingerprint == fingerprint({"seed": [1, 2], "data": digest(b"x")})
    text = record.to_text()
    assert json.loads(text)["format"] == "pokerirl-unit/2"
    assert UnitRecord.from_json(json.loads(text)) == record
    nan = UnitRecord.make({"seed": 1}, result={"p_value": float("nan")})  # an even matchup
    assert math.isnan(UnitRecord.from_json(json.loads(nan.to_text())).result["p_value"])
    with pytest.raises(ValueError, match="'seed' is both a setting and an input"):
        UnitRecord.make({"seed": 1}, inputs={"seed": digest(b"x")})


def test_a_unit_folder_written_before_the_store_is_reused(tmp_path: Path) -> None:
    folder = old_run_folder(tmp_path)
    record = read_record(folder / "unit.json")
    assert record is not None and record.format == "pokerirl-unit/1"
    assert record.identity == CONFIG_V1 and record.inputs == {}
    found = check(run_unit(folder))
    assert found.fate is Fate.REUSED and found.record == record
    assert (folder / "unit.json").read_text() == FOLDER_RECORD_V1  # never rewritten


def test_another_configuration_is_refused_in_one_line_naming_the_folder(tmp_path: Path) -> None:
    folder = old_run_folder(tmp_path)
    with pytest.raises(UnitConflict) as refused:
        check(run_unit(folder, epochs=3))
    message = str(refused.value)
    assert message == f"{folder} was made with another configuration (settings.epochs 2 -> 3)"
    assert "--" not in message  # the library names no flag; the command line adds the advice
    assert report(refused.value, ADVICE) == (
        1,
        f"{message}; use another --out, or --overwrite to recompute it",
    )
    assert refused.value.remedy is Remedy.RECOMPUTE
    found = check(run_unit(folder, epochs=3), overwrite=True)
    assert found.fate is Fate.RECOMPUTED and "settings.epochs 2 -> 3" in (found.why or "")


@pytest.mark.parametrize("damage", ["reward.pt", "unit.json", "both"])
def test_a_corrupt_unit_is_recomputed_whatever_its_configuration(
    tmp_path: Path, damage: str
) -> None:
    folder = old_run_folder(tmp_path)
    if damage in ("reward.pt", "both"):
        (folder / "reward.pt").write_bytes(b"weight")  # truncated
    if damage in ("unit.json", "both"):
        (folder / "unit.json").write_text(FOLDER_RECORD_V1[:50])
    for unit in (run_unit(folder), run_unit(folder, epochs=3)):  # no refusal: nothing to keep
        found = check(unit)
        assert found.fate is Fate.RECOMPUTED, found


@pytest.mark.parametrize(
    "text", ["{not json", "[]", '"a string"', '{"format": 1}', "", '{"format": "pokerirl-unit/1"}']
)
def test_a_record_that_is_not_one_is_recomputed(tmp_path: Path, text: str) -> None:
    path = tmp_path / "seed-0.json"
    path.write_text(text)
    assert read_record(path) is None
    unit = Unit(key="seed 0", target=path, layout=Layout.RECORD, config=SEED_CONFIG)
    assert check(unit).fate is Fate.RECOMPUTED


def test_a_record_of_a_newer_pokerirl_is_refused_naming_the_file(tmp_path: Path) -> None:
    path = tmp_path / "seed-0.json"
    path.write_text(json.dumps({"format": "pokerirl-unit/3", "anything": 1}))
    unit = Unit(key="seed 0", target=path, layout=Layout.RECORD, config=SEED_CONFIG)
    with pytest.raises(UnitConflict, match=rf"^{path} was written by a newer pokerirl"):
        check(unit)
    assert check(unit, overwrite=True).fate is Fate.RECOMPUTED


def test_record_and_file_units_written_before_the_store_are_reused(tmp_path: Path) -> None:
    seed = tmp_path / "seeds" / "seed-0.json"
    seed.parent.mkdir()
    seed.write_text(SEED_RECORD_V1)
    unit = Unit(key="seed 0", target=seed, layout=Layout.RECORD, config=SEED_CONFIG)
    found = check(unit)
    assert found.fate is Fate.REUSED and found.record is not None
    assert found.record.result == {"estimate": {"mbb_per_hand": 1.5}}

    data = tmp_path / "MountainCar-v0" / "expert.parquet"
    data.parent.mkdir()
    data.write_bytes(b"table")
    (data.parent / "expert.unit.json").write_text(DATA_RECORD_V1)
    unit = Unit(key="data", target=data, layout=Layout.FILE, config=DATA_CONFIG)
    assert unit.record_path == data.parent / "expert.unit.json"
    assert check(unit).fate is Fate.REUSED
    data.write_bytes(b"tablE")  # the data changed under its record
    assert check(unit).fate is Fate.RECOMPUTED


def ingest_unit(root: Path, settings: dict[str, object]) -> Unit[None]:
    """A study's table as round 2 declares it: a file unit that the old stage record vouches
    for."""
    identity = {"stage": "ingest", "settings": settings}
    return Unit(
        key="ingest",
        target=root / "expert.parquet",
        layout=Layout.FILE,
        config={"unit": "poker-ingest", "settings": settings},
        legacy=(LegacyRecord(path=root / "stages" / "ingest.json", identity=identity),),
    )


def test_a_study_stage_record_vouches_for_its_outputs(tmp_path: Path) -> None:
    root = tmp_path / "study"
    (root / "stages").mkdir(parents=True)
    (root / "stages" / "ingest.json").write_text(STAGE_RECORD_V1)
    (root / "expert.parquet").write_bytes(b"table")
    record = read_record(root / "stages" / "ingest.json")
    assert record is not None and record.format == "pokerirl-study-stage/1"
    assert record.fingerprint == fingerprint({"stage": "ingest", "settings": INGEST_SETTINGS})
    found = check(ingest_unit(root, INGEST_SETTINGS))
    assert found.fate is Fate.REUSED and found.record == record
    assert found.record.result == {"summary": {"rows": 10}}

    other = {"sources": {"files": [["/data/199504/hroster", 11, 1]]}}
    with pytest.raises(UnitConflict) as refused:
        check(ingest_unit(root, other))
    assert str(refused.value).startswith(f"{root / 'stages' / 'ingest.json'} was made with")
    assert "\n" not in str(refused.value)
    assert check(ingest_unit(root, other), overwrite=True).fate is Fate.RECOMPUTED

    (root / "expert.parquet").unlink()  # finished, but its table is gone: computed again
    assert check(ingest_unit(root, INGEST_SETTINGS)).fate is Fate.RUN


def test_an_unfinished_stage_is_resumed_and_its_own_record_comes_first(tmp_path: Path) -> None:
    root = tmp_path / "study"
    (root / "stages").mkdir(parents=True)
    started = json.loads(STAGE_RECORD_V1)
    started["finished"] = False
    del started["result"]
    (root / "stages" / "ingest.json").write_text(json.dumps(started))
    unit = ingest_unit(root, INGEST_SETTINGS)
    assert check(unit).fate is Fate.RUN
    (root / "expert.parquet").write_bytes(b"half")
    assert check(unit).fate is Fate.RECOMPUTED
