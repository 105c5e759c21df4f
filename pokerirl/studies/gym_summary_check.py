"""Check a gym study's ``summary.json`` once, on reading, before the report renders it.

``pokerirl report DIR`` renders a study's report again from its summary. A summary edited by
hand, truncated or written by another version must fail in one line that names the field, not
deep inside the renderer. Only the fields the report reads are checked; others may be added.

>>> check_task_summary({"env": "Acrobot-v1"})
Traceback (most recent call last):
...
pokerirl.errors.InputError: runs: missing
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from pokerirl.errors import InputError
from pokerirl.gym.presets import TASKS

Check = Callable[[Any, str], None]


def _fail(where: str, expected: str, value: Any) -> None:
    raise InputError(f"{where}: must be {expected}, got {value!r}"[:300])


def _number(value: Any, where: str) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        _fail(where, "a number", value)


def _optional_number(value: Any, where: str) -> None:
    if value is not None:
        _number(value, where)


def _count(value: Any, where: str) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        _fail(where, "a positive integer", value)


def _flag(value: Any, where: str) -> None:
    if not isinstance(value, bool):
        _fail(where, "true or false", value)


def _text(value: Any, where: str) -> None:
    if not isinstance(value, str):
        _fail(where, "a string", value)


def _task(value: Any, where: str) -> None:
    # Any Gymnasium id (issue 34): the report needs a name, not one of the paper's tasks.
    if not isinstance(value, str) or not value:
        _fail(where, f"an environment id (e.g. {', '.join(TASKS)})", value)


def _seeds(value: Any, where: str) -> None:
    if not isinstance(value, list) or not value:
        _fail(where, "a non-empty list of seeds", value)
    for k, seed in enumerate(value):
        if isinstance(seed, bool) or not isinstance(seed, int):
            _fail(f"{where}[{k}]", "an integer", seed)


def _fields(fields: Mapping[str, Check], *, optional: bool = False) -> Check:
    """A JSON object holding ``fields``; ``optional``: the object may also be null."""

    def check(value: Any, where: str) -> None:
        if value is None and optional:
            return
        if not isinstance(value, dict):
            _fail(where or "summary", "an object", value)
        for name, field in fields.items():
            inner = f"{where}.{name}" if where else name
            if name not in value:
                if field in _MAY_BE_ABSENT:
                    continue
                raise InputError(f"{inner}: missing")
            field(value[name], inner)

    return check


def _absent_or(check: Check) -> Check:
    """A field that older summaries lack (or hold as null)."""

    def field(value: Any, where: str) -> None:
        if value is not None:
            check(value, where)

    _MAY_BE_ABSENT.add(field)
    return field


_MAY_BE_ABSENT: set[Check] = set()

# {"mean": ..., "std": ...} or null: a final value over runs.
_MEAN_STD = _fields(
    {"mean": _optional_number, "std": _absent_or(_number)},
    optional=True,
)


# What the report shows of the runs' reward_quality.json (summaries before it lack them).
_QUALITY_SCORES = (
    "epic",
    "epic_random_baseline",
    "epic_expert_coverage",
    "epic_random_baseline_expert_coverage",
    "pearson_expert",
    "pearson_policy",
)
_QUALITY = _absent_or(
    _fields(
        {
            "true_reward": _fields({"kind": _text, "description": _text}),
            "coverage": _fields({"states": _text, "actions": _text}),
            "gamma": _number,
        }
    )
)


def _algo(discrete: bool) -> Check:
    fields: dict[str, Check] = {
        "irl_final_return": _MEAN_STD,
        "rl_final_return": _MEAN_STD,
        "reward_quality": _QUALITY,
        **{name: _absent_or(_MEAN_STD) for name in _QUALITY_SCORES},
    }
    if discrete:
        fields |= {
            "final_alignment": _MEAN_STD,
            "final_reward_alignment": _MEAN_STD,
            "baselines": _fields({"bc": _MEAN_STD}),
        }
    return _fields(fields)


def _paper(discrete: bool) -> Check:
    fields: dict[str, Check] = {
        "irl_final_return": _fields({"airl": _MEAN_STD, "hairl": _MEAN_STD}),
        "rl_final_return": _fields(
            {"airl": _MEAN_STD, "hairl": _MEAN_STD, "env_reward": _MEAN_STD}
        ),
        "expert_return": _optional_number,
        "random_return": _optional_number,
    }
    if discrete:
        fields["final_alignment"] = _fields({"airl": _optional_number, "hairl": _optional_number})
    return _fields(fields, optional=True)  # null: a task the paper does not have


_SETTINGS = _fields(
    {
        "irl": _fields(
            {
                "transitions": _count,
                "epochs": _count,
                "batch_size": _count,
                "alpha": _number,
                "beta": _number,
                "sigma_start": _number,
                "sigma_end": _number,
                "eval_episodes": _count,
            }
        ),
        "rl": _fields({"algo": _text, "timesteps": _count}),
        "rl_eval_episodes": _count,
        "authors_budget": _flag,
    }
)

_REWARD_MAP = _absent_or(
    _fields(
        {
            "agreement": _fields(
                {"airl": _fields({"mean_f": _number}), "hairl": _fields({"mean_f": _number})}
            ),
            "grid": _count,
            "constant_agreement": _number,
        }
    )
)


def check_task_summary(summary: Any, where: str = "") -> None:
    """Raise a one-line ``InputError`` naming the first field of a task's summary that the
    report cannot render (missing, or of the wrong type)."""
    _fields({"env": _task, "runs": _count, "seeds": _seeds, "discrete": _flag})(summary, where)
    discrete = summary["discrete"]
    _fields(
        {
            "expert_return": _optional_number,
            "random_return": _optional_number,
            "algos": _fields({"airl": _algo(discrete), "hairl": _algo(discrete)}),
            "env_reward": _fields({"rl_final_return": _MEAN_STD}),
            "paper": _paper(discrete),
            "settings": _SETTINGS,
            "reward_map": _REWARD_MAP,
        }
    )(summary, where)


def check_summary(found: Any) -> None:
    """A study's ``summary.json``: one task's, or ``all``'s (``tasks`` by env, and ``preset``)."""
    if not isinstance(found, dict):
        _fail("summary", "an object", found)
    _fields({"preset": _text})(found, "")
    if "tasks" not in found:
        check_task_summary(found)
        return
    tasks = found["tasks"]
    if not isinstance(tasks, dict) or not tasks:
        _fail("tasks", "an object of task summaries", tasks)
    for env, summary in tasks.items():
        check_task_summary(summary, f"tasks.{env}")
        if summary["env"] != env:
            _fail(f"tasks.{env}.env", repr(env), summary["env"])
