"""Reliability 4 (issue 36): hostile reward files, weights that are not numbers, counts that
would take the machine down, and lines that name what is wrong. Each test failed before."""

from __future__ import annotations

import os
import time
import warnings
import zipfile
from pathlib import Path

import pytest
import torch
from torch import nn
from torch.nn import functional
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.errors import InputError, PokerIRLError
from pokerirl.poker.reward_sources import RewardSource


class Discriminator(nn.Module):
    """The authors' reward net's layout (silue-dev/hairl), saved whole as they saved it."""

    def __init__(self) -> None:
        super().__init__()
        self.layers = nn.ModuleList([nn.Linear(65, 64)])
        self.output_layer = nn.Linear(64, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.output_layer(functional.leaky_relu(self.layers[0](x)))


@pytest.fixture(scope="module")
def authors_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("hostile") / "reward.model"
    torch.save(Discriminator(), path)
    return path


def _copy_with(source: Path, target: Path, member: str, data: bytes) -> Path:
    """``source`` with ``member`` replaced by ``data`` (deflated)."""
    with zipfile.ZipFile(source) as old, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as new:
        for info in old.infolist():
            payload = data if info.filename.endswith(member) else old.read(info)
            new.writestr(info.filename, payload)
    return target


def _refused(spec: str, message: str) -> str:
    with pytest.raises(PokerIRLError, match=message) as error:  # InputError, or a run's RunError
        RewardSource.resolve(spec)
    text = str(error.value)
    assert "\n" not in text
    return text


def test_a_zip_bomb_member_is_refused_before_it_is_inflated(
    authors_file: Path, tmp_path: Path
) -> None:
    bomb = _copy_with(authors_file, tmp_path / "bomb.model", "data.pkl", b"\0" * (64 << 20))
    assert bomb.stat().st_size < 1 << 20  # 64 MiB of zeros deflate to about 64 KB
    started = time.perf_counter()
    text = _refused(f"authors:{bomb}", "member data.pkl declares 67,108,864 bytes")
    assert str(bomb) in text and time.perf_counter() - started < 5


def test_a_central_directory_that_declares_4_gib_is_one_line(
    authors_file: Path, tmp_path: Path
) -> None:
    data = bytearray(authors_file.read_bytes())
    with zipfile.ZipFile(authors_file) as archive:
        info = next(i for i in archive.infolist() if i.filename.endswith("data.pkl"))
    # The central directory's uncompressed size of data.pkl: its record, 24 bytes in.
    name = info.filename.encode()
    record = data.find(b"PK\x01\x02")
    while data[record + 46 : record + 46 + len(name)] != name:
        record = data.find(b"PK\x01\x02", record + 4)
    data[record + 24 : record + 28] = (0xFFFFFFFE).to_bytes(4, "little")
    huge = tmp_path / "huge.model"
    huge.write_bytes(bytes(data))
    _refused(f"authors:{huge}", "data.pkl declares 4,294,967,294 bytes")


def test_a_file_too_large_a_folder_and_a_device_are_named(
    authors_file: Path, tmp_path: Path
) -> None:
    sparse = tmp_path / "sparse.model"
    with sparse.open("wb") as stream:
        stream.truncate(2 << 30)  # 2 GiB, sparse: nothing is read
    _refused(f"authors:{sparse}", "2,147,483,648 bytes, more than the 1,048,576 it may hold")
    _refused(f"authors:{tmp_path}", "is a folder, not a file")
    zero = tmp_path / "zero.model"
    os.symlink("/dev/zero", zero)
    _refused(f"authors:{zero}", "not a regular file")
    _refused(f"authors:{tmp_path / 'none.model'}", "no such file")


def test_a_flipped_byte_inside_a_member_is_one_line(authors_file: Path, tmp_path: Path) -> None:
    data = bytearray(authors_file.read_bytes())
    with zipfile.ZipFile(authors_file) as archive:
        info = next(i for i in archive.infolist() if i.filename.endswith("data/0"))
    start = info.header_offset + 30 + len(info.filename.encode()) + len(info.extra)
    data[start + 100] ^= 0xFF  # inside data/0's stored bytes: its CRC no longer matches
    flipped = tmp_path / "flipped.model"
    flipped.write_bytes(bytes(data))
    _refused(f"authors:{flipped}", "damaged zip member")
    result = CliRunner().invoke(app, ["reward-card", f"authors:{flipped}", "--table", "t.parquet",
                                      "--out", str(tmp_path / "card")])  # fmt: skip
    assert result.exit_code == 1 and result.output.count("\n") == 1, result.output


@pytest.fixture(scope="module")
def poker_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    import pyarrow.parquet as pq

    from pokerirl.datasets.toy import toy_expert_table
    from pokerirl.irl import load_config
    from pokerirl.poker import train_table

    root = tmp_path_factory.mktemp("run")
    pq.write_table(toy_expert_table(num_hands=80, seed=1), root / "table.parquet")
    train_table(root / "table.parquet", root / "run", progress=False,
                config=load_config("hairl", overrides={"epochs": 1, "batch_size": 32}))  # fmt: skip
    return root / "run"


def test_non_finite_reward_and_agent_weights_are_refused(poker_run: Path, tmp_path: Path) -> None:
    from pokerirl.agents.checkpoint import load_agent, save_agent
    from pokerirl.agents.dqn import QNetwork

    nan_run = tmp_path / "nan-run"
    nan_run.mkdir()
    (nan_run / "config.json").write_bytes((poker_run / "config.json").read_bytes())
    state = torch.load(poker_run / "reward.pt", weights_only=True)
    first = next(iter(state))
    state[first][0, 0] = float("nan")
    torch.save(state, nan_run / "reward.pt")
    _refused(str(nan_run), rf"reward.pt: weights hold NaN or infinity \({first}\)")
    network = QNetwork(hidden=(8,))
    with torch.no_grad():
        network.mlp[0].bias.fill_(float("inf"))
    save_agent(tmp_path / "agent", network, {"hidden": [8]})
    with pytest.raises(InputError, match="weights hold NaN or infinity"):
        load_agent(tmp_path / "agent")


def test_a_plain_pickle_reward_is_one_line_without_torch_warnings(
    poker_run: Path, tmp_path: Path
) -> None:
    import pickle

    run = tmp_path / "pickled"
    run.mkdir()
    (run / "config.json").write_bytes((poker_run / "config.json").read_bytes())
    (run / "reward.pt").write_bytes(pickle.dumps({"weights": [1, 2, 3]}, protocol=4))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _refused(str(run), "not a readable PyTorch state_dict")
    assert [str(w.message) for w in caught] == []


def test_counts_that_would_take_the_machine_down_are_usage_errors(tmp_path: Path) -> None:
    for args in (
        ["gym", "rl", "MountainCar-v0", "--runs", "100000000", "--out", str(tmp_path / "a")],
        ["gym", "study", "MountainCar-v0", "--runs", "100000000", "--out", str(tmp_path / "b")],
        ["train", "t.parquet", "--runs", "100000000", "--out", str(tmp_path / "c")],
        ["study", str(tmp_path), "--runs", "100000000", "--out", str(tmp_path / "d")],
    ):
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 2 and "less than or equal to 10000" in result.output, args
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_transfer_refuses_a_repeated_seed_before_any_work(poker_run: Path, tmp_path: Path) -> None:
    args = ["transfer", str(poker_run), "--seeds", "0,0", "--out", str(tmp_path / "t")]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2 and "seed 0 is given twice" in result.output
    assert not (tmp_path / "t").exists()


def test_a_gym_reward_that_does_not_fit_names_its_run(poker_run: Path) -> None:
    pytest.importorskip("gymnasium")
    from pokerirl.gym.rl import check_reward
    from pokerirl.irl import load_reward

    with pytest.raises(InputError, match=f"the reward of {poker_run} does not fit MountainCar"):
        check_reward("MountainCar-v0", load_reward(poker_run), f"the reward of {poker_run}")


def test_a_ray_address_that_is_not_a_head_is_refused_before_any_work(tmp_path: Path) -> None:
    import http.server
    import threading

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args: object) -> None:  # the server's own log is not the CLI's
            pass

    server = http.server.HTTPServer(("127.0.0.1", 0), Quiet)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        address = f"127.0.0.1:{server.server_address[1]}"
        started = time.perf_counter()
        args = ["gym", "study", "MountainCar-v0", "--preset", "quick", "--ray", address,
                "--out", str(tmp_path / "g")]  # fmt: skip
        result = CliRunner().invoke(app, args)
    finally:
        server.shutdown()
    assert result.exit_code == 1 and "an HTTP server answers there" in result.output
    assert result.output.count("\n") == 1, result.output  # no progress line before it
    assert not (tmp_path / "g").exists() and time.perf_counter() - started < 15


def test_a_parquet_footer_that_declares_more_than_the_file_holds_is_refused(
    tmp_path: Path,
) -> None:
    """A footer declaring 2^31 rows and 2 GB in a small file: refused before any row is read
    (a stub of the footer: pyarrow writes only true ones); a true table passes."""
    from types import SimpleNamespace

    import pyarrow.parquet as pq

    from pokerirl.datasets.toy import toy_expert_table
    from pokerirl.parquet import check_footer, read_parquet

    chunk = SimpleNamespace(total_compressed_size=1_000)
    group = SimpleNamespace(total_byte_size=2 << 30, num_columns=1, column=lambda j: chunk)
    lying = SimpleNamespace(num_rows=2**31, num_row_groups=1, row_group=lambda i: group)
    with pytest.raises(InputError, match="declares 2,147,483,648 rows and 2,147,483,648 bytes"):
        check_footer(lying, 100_000, "t.parquet")  # type: ignore[arg-type]
    chunk.total_compressed_size = 200_000
    group.total_byte_size = 1_000
    with pytest.raises(InputError, match="a column chunk larger than the file"):
        check_footer(lying, 100_000, "t.parquet")  # type: ignore[arg-type]
    pq.write_table(toy_expert_table(num_hands=50), tmp_path / "true.parquet")
    assert read_parquet(tmp_path / "true.parquet", ["obs"], what="table").num_rows > 50
    # A true footer, but 500,000 copies of one row: dictionary and run-length encoding hold
    # them in a few KB (8M such rows in 716 KB cost `train` 8.4 GB before this check).
    import pyarrow as pa

    one = toy_expert_table(num_hands=2).slice(0, 1)
    pq.write_table(one.take(pa.array([0] * 500_000)), tmp_path / "runs.parquet")
    with pytest.raises(InputError, match=r"500,000 rows in a file of [\d,]+ bytes, more than 1"):
        read_parquet(tmp_path / "runs.parquet", ["obs"], what="table")


def test_nan_or_infinity_in_a_gym_table_is_one_line(tmp_path: Path) -> None:
    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq

    from pokerirl.irl import Transitions

    n = 20
    obs = np.zeros((n, 2), np.float32)
    obs[7, 1] = np.nan
    columns = {
        "obs": pa.FixedSizeListArray.from_arrays(pa.array(obs.reshape(-1)), 2),
        "next_obs": pa.FixedSizeListArray.from_arrays(pa.array(np.zeros(2 * n, np.float32)), 2),
        "action": pa.array(np.zeros(n, np.int64)),
        "reward": pa.array(np.full(n, np.inf, np.float32)),
        "done": pa.array(np.zeros(n, bool)),
        "episode": pa.array(np.arange(n) // 5),
    }
    pq.write_table(pa.table(columns), tmp_path / "rollouts.parquet")
    with pytest.raises(InputError, match=r"column 'obs' holds NaN or infinity \(1 row\(s\), the "
                       "first row 7\\)"):  # fmt: skip
        Transitions.from_parquet(tmp_path / "rollouts.parquet")


def test_a_reward_card_table_whose_mask_forbids_the_expert_is_one_line(
    poker_run: Path, tmp_path: Path
) -> None:
    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pq.read_table(poker_run.parent / "table.parquet")
    masks = np.array(table.column("legal_mask").to_pylist(), bool)
    forbidden, empty = masks.copy(), masks.copy()
    forbidden[0, table.column("action_id")[0].as_py()] = False
    empty[1] = False
    for name, mask, message in (
        ("forbidden", forbidden, "1 row(s) take an action their 'legal_mask' forbids"),
        ("empty", empty, "1 row(s) have no legal action in 'legal_mask'"),
    ):
        column = pa.array(mask.tolist(), table.schema.field("legal_mask").type)
        index = table.column_names.index("legal_mask")
        pq.write_table(table.set_column(index, "legal_mask", column), tmp_path / f"{name}.parquet")
        args = ["reward-card", str(poker_run), "--table", str(tmp_path / f"{name}.parquet"),
                "--out", str(tmp_path / name)]  # fmt: skip
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 1, result.output
        assert result.output.count("\n") == 1 and message in result.output, result.output
        assert not (tmp_path / name / "reward_card.json").exists()


def test_a_folder_without_irc_data_is_the_error_line_alone(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    for args in (
        ["ingest", str(tmp_path / "empty"), "--out", str(tmp_path / "table.parquet")],
        ["study", str(tmp_path / "empty"), "--out", str(tmp_path / "study")],
    ):
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 1
        assert result.output == f"error: {tmp_path / 'empty'}: no IRC data here (no hdb file " \
            "and no .tgz archive)\n", args  # fmt: skip
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty"]


def test_study_names_a_bad_reward_algorithm_and_transform(tmp_path: Path) -> None:
    for option, value in (("--reward-run", "nope=authors:F"), ("--reward-transform", "nope")):
        args = ["study", str(tmp_path), "--out", str(tmp_path / "s"), option, value]
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 2 and "(got 'nope')" in result.output, result.output
