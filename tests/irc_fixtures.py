"""Hand-written IRC months, one hand per quirk of the format (10-20 limit, blinds 5/10), and
the real April 1995 sample that pokerirl ships (:func:`real_month`)."""

from __future__ import annotations

import atexit
import functools
import shutil
import tempfile
from pathlib import Path

from pokerirl.datasets.catalog import unpack_sample

# The CI checkout's copy of the real sample, beside the repository (or beside a folder of
# worktrees): only the test that the shipped archive is these bytes reads it.
_ABOVE = Path(__file__).resolve().parents[1:4]
_SHARED = [p / "shared" / "irc-sample" / "holdem" / "199504" for p in _ABOVE]
SHARED_SAMPLE = next((p for p in _SHARED if p.is_dir()), _SHARED[0])


@functools.cache
def real_month() -> Path:
    """The shipped sample (``irc-199504``) as a month folder ``.../holdem/199504``, unpacked
    once per process into a temporary folder removed at exit: the real hands the tests read,
    with nothing beside the clone."""
    root = Path(tempfile.mkdtemp(prefix="pokerirl-irc-199504-"))
    atexit.register(shutil.rmtree, root, ignore_errors=True)
    return unpack_sample(root)


ZED_FIRST = 800000001  # standard showdown; roster in name order (Amy before Zed), Zed sits 1
NO_CAP = 800000002  # five raises preflop: past RLCard's cap of four
FOLDED = 800000003  # ends with a fold: nobody's cards are shown
ALL_IN = 800000004  # "A" facing a bet is an all-in call
KICKED = 800000005  # "K" (kicked) is a fold
LONE_BLIND = 800000006  # only position 1 posts, a full blind; position 2 acts first
MISSING_PDB = 800000007  # Amy's pdb line is missing
THREE_WAY = 800000008  # not heads-up
ODD_NICK = 800000009  # a nick with . [ ] ` and \ in it, from a file named otherwise
ROSTER_MISMATCH = 800000010  # hroster names Bob, pdb says Zed

HDB = [
    f"{ZED_FIRST}   1   1  2  2/20    2/40    2/80     2/80     2c 7d 9h Ts Js",
    f"{NO_CAP}   1   2  2  2/120   2/120   2/120    2/120    3c 4d 8h 9s Kd",
    f"{FOLDED}   1   3  2  0/0     0/0     0/0      1/15     ",
    f"{ALL_IN}   1   4  2  2/20    2/35    2/35     2/35     2c 3c 4c 5d 9h",
    f"{KICKED}   1   5  2  2/20    0/0     0/0      1/30     6c 7c 8c",
    f"{LONE_BLIND}   1   6  2  2/20    2/20    2/20     2/20     2d 5h 9c Jd Ks",
    f"{MISSING_PDB}   1   7  2  2/20    2/20    2/20     2/20     2d 5h 9c Jd Ks",
    f"{THREE_WAY}   1   8  3  2/30    2/30    2/30     2/30     2d 5h 9c Jd Ks",
    f"{ZED_FIRST}   1   1  2  2/20    2/40    2/80     2/80     2c 7d 9h Ts Js",  # duplicate
    "this is not an hdb line",
    f"{ODD_NICK}   1   9  2  2/20    2/20    2/20     2/20     2d 5h 9c Jd Ks",
    f"{ROSTER_MISMATCH}   1  10  2  2/20    2/20    2/20     2/20     2d 5h 9c Jd Ks",
]

ODD = "[Odd].Nick`\\"

HROSTER = [
    f"{ZED_FIRST}  2 Amy Zed",
    f"{NO_CAP}  2 Amy Zed",
    f"{FOLDED}  2 Amy Zed",
    f"{ALL_IN}  2 Amy Zed",
    f"{KICKED}  2 Amy Zed",
    f"{LONE_BLIND}  2 Amy Zed",
    f"{MISSING_PDB}  2 Amy Zed",
    f"{THREE_WAY}  3 Amy Bob Zed",
    f"{ODD_NICK}  2 Amy {ODD}",
    f"{ROSTER_MISMATCH}  2 Amy Bob",
]

PDB = {
    "pdb.Amy": [
        f"Amy       {ZED_FIRST}  2  2 Bk  b     c     k         1000   40   80 Kc Qc",
        f"Amy       {NO_CAP}  2  1 Brrr k     k     k         1040   60  120 Ah Ac",
        f"Amy       {FOLDED}  2  1 Bf  -     -     -         1100    5    0 ",
        f"Amy       {ALL_IN}  2  2 Bk  A     -     -           15   15   30 Ac Kd",
        f"Amy       {KICKED}  2  1 Bc  bQ    -     -         1100   20   30 ",
        f"Amy       {LONE_BLIND}  2  2 c   k     k     k         1110   10    0 3h 4h",
        f"Amy       {THREE_WAY}  3  1 Bc  k     k     k         1100   10    0 3h 4h",
        f"Amy       {ODD_NICK}  2  1 Bc  k     k     k         1100   10   20 Ah Kh",
        f"Amy       {ROSTER_MISMATCH}  2  1 Bc  k     k     k         1100   10   20 Ah Kh",
    ],
    "pdb.Zed": [
        f"Zed       {ZED_FIRST}  2  1 Bc  kc    b     k         1000   40    0 As Ad",
        f"Zed       {NO_CAP}  2  2 Brrc k     k     k          960   60    0 2h 2s",
        f"Zed       {FOLDED}  2  2 B   -     -     -          900   10   15 ",
        f"Zed       {ALL_IN}  2  1 Bc  b     -     -          905   20    5 Qs Qh",
        f"Zed       {KICKED}  2  2 Bk  K     -     -          890   10    0 ",
        f"Zed       {LONE_BLIND}  2  1 Bk  k     k     k          880   10   20 Qd Qh",
        f"Zed       {MISSING_PDB}  2  1 Bc  k     k     k          890   10   20 Qd Qh",
        f"Zed       {THREE_WAY}  3  2 Bk  k     k     k          890   10   30 Qd Qh",
        f"Zed       {ROSTER_MISMATCH}  2  2 Bk  k     k     k          890   10    0 Qd Qh",
    ],
    "pdb.Bob": [
        f"Bob       {THREE_WAY}  3  3 Bk  k     k     k          500   10    0 7s 7d",
    ],
    # The file name need not match the nick: read the nick from the line.
    "pdb.Odd.Nick": [
        f"{ODD} {ODD_NICK}  2  2 Bk  k     k     k          700   10    0 Qd Qh",
    ],
}


def write_month(
    root: Path,
    channel: str = "holdem",
    month: str = "199504",
    *,
    hdb: list[str] = HDB,
    hroster: list[str] = HROSTER,
    pdb: dict[str, list[str]] = PDB,
    newline: str = "\r\n",
) -> Path:
    """Write a month folder ``root/channel/month`` and return it."""
    folder = root / channel / month
    (folder / "pdb").mkdir(parents=True, exist_ok=True)

    def write(path: Path, lines: list[str]) -> None:
        path.write_bytes("".join(line + newline for line in lines).encode("latin-1"))

    write(folder / "hdb", hdb)
    write(folder / "hroster", hroster)
    for name, lines in pdb.items():
        write(folder / "pdb" / name, lines)
    return folder
