"""AIRL and H-AIRL keep their bytes: trained parameters and metrics, pinned.

The digests were computed on main at 820abee (before the discriminator became a strategy,
issue 35) and were the same on two runs there; the same script then gave the same digests
after the change, together with those of `pokerirl train` and `pokerirl gym irl` run
folders. Floating point depends on torch's build and the CPU's vector unit, so the pins
hold only where they were made; elsewhere the test is skipped, saying why.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

import numpy as np
import pytest
import torch

from pokerirl.irl import AIRLConfig, Transitions, train, train_many

PINNED_ON = ("2.14.1+cu130", "AVX2")  # torch.__version__, torch's CPU capability

# case: (discrete?, algo, overrides) -> {"fast": ..., "autograd": ..., "many": ...}
CASES: dict[str, tuple[bool, str, dict[str, Any]]] = {
    "d-airl": (True, "airl", {}),
    "d-hairl": (True, "hairl", {"beta": 0.3}),
    "d-hairl-dist-authors": (True, "hairl", {
        "disc_action": "distribution", "noise_schedule": "authors", "supervised_form": "sum_mse",
    }),
    "d-airl-shaped": (True, "airl", {"reward_family": "shaped"}),
    "c-hairl-authors": (False, "hairl", {
        "noise_form": "authors", "noise_schedule": "authors", "supervised_form": "sum_mse",
        "disc_action": "distribution",
    }),
    "c-airl-shaped": (False, "airl", {"reward_family": "shaped"}),
}  # fmt: skip
PINS = {
    "d-airl": {
        "fast": "d47fe71d7d75105858e8fddbd6071b87bbd4b5ac9aeb3474cbcaacdce880b1e5 6eb47cb281a0bf54",
        "autograd": "4046e4c8895bf3c93e09dc82231dc27954633e7d5f9884d2e2c6b2ba660eb9d2"
        " 9415bed895017279",
        "many": "540029b81c36c3c3a67963451886bd19252e932bd027d37151c14e813e0fdf9b",
    },
    "d-hairl": {
        "fast": "388babcc42b35dead26ad4f5f3aa33effd398cd8bdf936a7cfab234f861f9a2b bff8bff80df79ba3",
        "autograd": "6e3eab1107aed7a2c930499085a77425921eb4acb3ec83bdcd5290a34606e22f"
        " 1e0993a7682a4623",
        "many": "f8e638d04ddb24ce96254158bc1eda4231c65d7a453249a919c1dfac69f7ac5c",
    },
    "d-hairl-dist-authors": {
        "autograd": "8ca1ac675402b75843dd98f7b3bd8002c56023e8c5c249add0fb1139b56a0324"
        " d6d57df605de126d",
        "many": "9992ce957ddf95ed8e0a8fa41863d155dc51b1a4f7f77058d60c87371c5a22ae",
    },
    "d-airl-shaped": {
        "autograd": "4bf59e437c6601bbcad86275e5fe40ac0f5be0fb17c1b419749c50e8b25ec118"
        " 859b47592edd692e",
        "many": "01c03f006f26ff41b52525f9981d6bc64107bffa874f626d2cc00e61ea12b390",
    },
    "c-hairl-authors": {
        "autograd": "dfab8d86d17fe6a929d8a19d7d31b4197abbae776554b8f050b15af566a6f7e9"
        " 73eda03d061af606",
        "many": "bf9384c0268fdc9d9a167b1295f666ed49c56ea15ad862fc5cea59d6b7b6ff4e",
    },
    "c-airl-shaped": {
        "autograd": "bfa9910ad6d04d686507306183219a52de33bf90f43168a15d52198115414f68"
        " 9d8473eea8deeeb3",
        "many": "426c86897cb258ad20e45b8fccf008d36c3da1cfd7133773e0a20abeb45827cb",
    },
}
WEIGHTED_PINS = {
    "airl": "350bc51817b73299baf8dd6862ad101019e898409a2de44adfe39e7ec3034996",
    "hairl": "44a29bc33cd2ee9f245163b42d638ae5eb020aaf5f846b0c6ea5a5971ef1d1b6",
}


def _here() -> tuple[str, str]:
    return torch.__version__, torch.backends.cpu.get_cpu_capability()


pytestmark = pytest.mark.skipif(
    _here() != PINNED_ON, reason=f"digests pinned on torch {PINNED_ON}, here {_here()}"
)


def _params(*modules: torch.nn.Module) -> str:
    digest = hashlib.sha256()
    for module in modules:
        for key, value in module.state_dict().items():
            digest.update(key.encode())
            digest.update(value.detach().cpu().numpy().tobytes())
    return digest.hexdigest()


def _data() -> tuple[Transitions, Transitions, np.random.Generator]:
    rng = np.random.default_rng(0)
    obs = rng.random((300, 5)).astype(np.float32)
    common = {
        "groups": np.arange(300),
        "next_obs": rng.random((300, 5)).astype(np.float32),
        "dones": rng.random(300) < 0.2,
        "rewards": rng.random(300).astype(np.float32),
    }
    actions = (obs[:, 0] > 0.5).astype(np.int64) + (obs[:, 1] > 0.5)
    discrete = Transitions.from_arrays(obs, actions, **common)
    box = Transitions.from_arrays(obs, obs[:, :2] * 2 - 1, low=[-1.0, -1.0], high=[1.0, 1.0],
                                  **common)  # fmt: skip
    return discrete, box, rng


@pytest.mark.parametrize("case", list(CASES))
def test_airl_and_hairl_runs_keep_their_bytes(case: str) -> None:
    discrete, box, _ = _data()
    is_discrete, algo, overrides = CASES[case]
    data = discrete if is_discrete else box
    config = AIRLConfig.for_algo(algo, epochs=2, batch_size=64, **overrides)
    for name, pin in PINS[case].items():
        if name == "many":
            many = train_many(data, data, config=config, seeds=[0, 1], progress=False)
            found = _params(*[r.reward for r in many.runs], *[r.policy for r in many.runs])
        else:
            run = train(data, data, config=config, fast_path=name == "fast", progress=False)
            assert run.gradients == ("hand-derived" if name == "fast" else "autograd")
            metrics = json.dumps([dict(m) for m in run.metrics], sort_keys=True).encode()
            found = f"{_params(run.reward, run.policy)} {hashlib.sha256(metrics).hexdigest()[:16]}"
        assert found == pin, name


@pytest.mark.parametrize("algo", ["airl", "hairl"])
def test_weighted_rows_keep_their_bytes(algo: str) -> None:
    discrete, _, rng = _data()
    obs = discrete.obs.numpy()
    weights = rng.random(300).astype(np.float32) + 0.5
    data = Transitions.from_arrays(obs, (obs[:, 0] > 0.5).astype(np.int64),
                                   groups=np.arange(300), weights=weights)  # fmt: skip
    run = train(data, data, config=AIRLConfig.for_algo(algo, epochs=2, batch_size=64),
                progress=False)  # fmt: skip
    assert _params(run.reward, run.policy) == WEIGHTED_PINS[algo]
