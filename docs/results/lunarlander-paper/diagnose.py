"""Why does PPO on H-AIRL's LunarLander reward do so badly? A reproducible diagnosis.

Usage (from the repository root)::

    PYTHONPATH=$PWD python docs/results/lunarlander-paper/diagnose.py /work/studies/lunar-paper

Reads a finished ``pokerirl gym study LunarLander-v3 --preset paper`` folder (read-only) and
writes ``diagnosis.json`` and ``diagnosis.png`` beside this script; prints the tables.

What it measures (everything seeded, single-threaded, deterministic):

1. Behaviour: each of the study's 9 RL policies (``rl/{env,airl,hairl}/run-k``) plays the
   20 deterministic episodes of the study's final evaluation (seeds ``EVAL_SEED + i``, the
   same starts, so the returns reproduce the study's last curve point), plus reference
   behaviours: the shipped expert (the one that made ``expert.parquet``), Gymnasium's
   heuristic lander, a hover controller (the heuristic with a fixed height target of 0.4,
   which never lands: 1000-step timeouts), do-nothing (free fall, crash) and uniformly random
   actions. Per episode: length, true return, how it ended, final state, engine firings.
2. What the learned rewards pay: the reward PPO was trained on is exactly
   ``pokerirl.irl.load_reward(irl run)`` called on (observation the action was taken in, the
   action) -- ``state_action`` family, standardization folded into the net, no transform or
   normalization, no next-state or terminal term (``pokerirl/gym/rewards.py``,
   ``pokerirl/gym/lockstep/ppo.py``). Every trajectory is scored by all six reward nets
   (``irl/{airl,hairl}/run-k``): mean f per step, episode sum, gamma-discounted sum
   (gamma = 0.999, the PPO settings'), f of the terminal transition; plus the whole expert
   data set (``expert.parquet``).
3. PPO's update at that reward scale: for each reward (and the env reward) one 960-step
   rollout of a fresh PPO policy (the study's architecture, seeded) and of each final policy;
   GAE returns as PPO computes them; the gradient norm of the policy-gradient term and of
   ``vf_coef * value loss`` on one 64-sample minibatch, and how much of the clipped
   (``max_grad_norm`` 0.6, one norm over both nets) step is left for the policy.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pokerirl.gym.collect import read_transitions
from pokerirl.gym.envs import make_env
from pokerirl.gym.expert_policies import build_policy, load_expert, resolve_expert_dir
from pokerirl.gym.presets import TASKS
from pokerirl.gym.rl import EVAL_SEED
from pokerirl.irl import load_reward

ENV = "LunarLander-v3"
EPISODES = 20  # the study's eval_episodes; seeds EVAL_SEED + i, as its final evaluation
RANDOM_SEED = 12345  # the random policy's action draws
GRAD_SEED = 7  # the PPO probes' fresh policies, action sampling and state sample
ADAM_EPS = 1e-5  # SB3 PPO's Adam (and the lock-step backend's)
SCALE = 0.01  # the counterfactual: the learned reward times this
HOVER_Y = 0.4  # the hover controller's height target (the pad is at y = 0)
ALGOS = ("airl", "hairl")
RL_REWARDS = ("env", "airl", "hairl")
RUNS = (0, 1, 2)
PPO = TASKS[ENV].rl.ppo
assert PPO is not None
GAMMA = PPO.gamma
HERE = Path(__file__).resolve().parent
warnings.filterwarnings("ignore", message=".*not writable.*")


# --------------------------------------------------------------------------- behaviours


def heuristic_action(s: np.ndarray, hover_y: float | None = None) -> int:
    """Gymnasium's ``lunar_lander.heuristic`` (discrete); ``hover_y``: a fixed height target
    instead of landing, and no touchdown branch (so it hovers until the 1000-step limit)."""
    angle_targ = float(np.clip(s[0] * 0.5 + s[2] * 1.0, -0.4, 0.4))
    target_y = 0.55 * abs(s[0]) if hover_y is None else hover_y
    angle_todo = (angle_targ - s[4]) * 0.5 - s[5] * 1.0
    hover_todo = (target_y - s[1]) * 0.5 - s[3] * 0.5
    if hover_y is None and (s[6] or s[7]):
        angle_todo, hover_todo = 0.0, -s[3] * 0.5
    if hover_todo > abs(angle_todo) and hover_todo > 0.05:
        return 2
    if angle_todo < -0.05:
        return 3
    if angle_todo > 0.05:
        return 1
    return 0


def sb3_actor(policy: Any):
    def act(obs: np.ndarray) -> int:
        action, _ = policy.predict(obs, deterministic=True)
        return int(action)

    return act


def load_rl_policy(run: Path) -> tuple[Any, dict]:
    config = json.loads((run / "config.json").read_text())
    policy = build_policy(ENV, "ppo", config["policy_kwargs"])
    policy.load_state_dict(torch.load(run / "model.pt", weights_only=True, map_location="cpu"))
    policy.set_training_mode(False)
    return policy, config


def play(act, seed: int) -> dict[str, Any]:
    """One episode from ``reset(seed=seed)``: the transitions and how it ended."""
    env = make_env(ENV)
    lander = env.unwrapped
    obs, _ = env.reset(seed=seed)
    states, actions, rewards = [], [], []
    while True:
        a = act(obs)
        states.append(np.asarray(obs, np.float32))
        actions.append(a)
        obs, r, terminated, truncated, _ = env.step(a)
        rewards.append(float(r))
        if terminated or truncated:
            break
    if truncated and not terminated:
        outcome = "timeout"
    elif not lander.lander.awake:  # the env's +100: came to rest
        outcome = "landed"
    elif abs(obs[0]) >= 1.0:
        outcome = "out_of_bounds"
    else:  # lander.game_over: the body touched the ground
        outcome = "crashed"
    env.close()
    acts = np.asarray(actions)
    return {
        "obs": np.stack(states), "actions": acts, "rewards": np.asarray(rewards),
        "final": np.asarray(obs, np.float64), "outcome": outcome,
        "on_pad": bool(abs(obs[0]) <= 0.2), "main": int((acts == 2).sum()),
        "side": int(((acts == 1) | (acts == 3)).sum()),
    }  # fmt: skip


def behaviours(study: Path) -> dict[str, dict[str, Any]]:
    """name -> {"episodes": [...], "kind": ..., "study_final": ...}."""
    seeds = [EVAL_SEED + i for i in range(EPISODES)]
    out: dict[str, dict[str, Any]] = {}
    for reward in RL_REWARDS:
        for k in RUNS:
            run = study / "rl" / reward / f"run-{k}"
            policy, config = load_rl_policy(run)
            act = sb3_actor(policy)
            out[f"rl/{reward}/run-{k}"] = {
                "kind": f"rl-{reward}", "reward": config["reward"], "run": k,
                "study_final": config["final_return"],
                "episodes": [play(act, s) for s in seeds],
            }  # fmt: skip
    expert = load_expert(resolve_expert_dir("shipped", ENV))
    out["expert"] = {"kind": "reference", "episodes": [play(sb3_actor(expert.policy), s)
                                                       for s in seeds]}  # fmt: skip
    out["heuristic"] = {"kind": "reference",
                        "episodes": [play(heuristic_action, s) for s in seeds]}  # fmt: skip
    out["hover"] = {"kind": "reference", "episodes": [
        play(lambda o: heuristic_action(o, HOVER_Y), s) for s in seeds]}  # fmt: skip
    out["noop"] = {"kind": "reference", "episodes": [play(lambda o: 0, s) for s in seeds]}
    rng = np.random.default_rng(RANDOM_SEED)
    out["random"] = {
        "kind": "reference",
        "episodes": [play(lambda o: int(rng.integers(4)), s) for s in seeds],
    }
    return out


# --------------------------------------------------------------------------- rewards


def discounted(f: np.ndarray) -> float:
    return float(np.sum(f * GAMMA ** np.arange(len(f))))


def score(episodes: list[dict], fn) -> dict[str, Any]:
    """What reward ``fn`` pays along ``episodes``."""
    fs = [np.asarray(fn(e["obs"], e["actions"]), np.float64) for e in episodes]
    per_step = np.concatenate(fs)
    by_outcome: dict[str, list[float]] = {}
    for e, f in zip(episodes, fs, strict=True):
        by_outcome.setdefault(e["outcome"], []).append(float(f[-1]))
    last10 = np.concatenate([f[-10:] for f in fs])
    return {
        "mean_f_per_step": float(per_step.mean()),
        "median_f_per_step": float(np.median(per_step)),
        "frac_steps_positive": float((per_step > 0).mean()),
        "episode_sum": float(np.mean([f.sum() for f in fs])),
        "episode_sum_std": float(np.std([f.sum() for f in fs])),
        "discounted_sum": float(np.mean([discounted(f) for f in fs])),
        "mean_f_last10": float(last10.mean()),
        "terminal_f_by_outcome": {k: float(np.mean(v)) for k, v in sorted(by_outcome.items())},
        "pearson_f_true_step": float(np.corrcoef(per_step, np.concatenate(
            [e["rewards"] for e in episodes]))[0, 1]),
        "_per_episode_f": fs,
    }  # fmt: skip


def expert_data_scores(study: Path, rewards: dict[str, Any]) -> dict[str, Any]:
    """The whole expert data set: complete episodes, by how they ended (their last reward)."""
    data = read_transitions(study / "expert.parquet")
    ep, done = data["episode"], data["done"]
    ends = np.flatnonzero(np.r_[ep[1:] != ep[:-1], True])
    starts = np.r_[0, ends[:-1] + 1]
    complete = [(a, b) for a, b in zip(starts, ends, strict=True)
                if done[b] or data["truncated"][b]]  # fmt: skip
    outcome = {(a, b): ("timeout" if not done[b] else "landed" if data["reward"][b] > 50
                        else "crash_or_oob") for a, b in complete}  # fmt: skip
    lengths = np.array([b - a + 1 for a, b in complete])
    out: dict[str, Any] = {
        "episodes": len(complete),
        "length_mean": float(lengths.mean()),
        "length_median": float(np.median(lengths)),
        "outcomes": {str(k): int(v) for k, v in zip(*np.unique(list(outcome.values()),
                                                               return_counts=True), strict=True)},
        "true_return_mean": float(np.mean([data["reward"][a:b + 1].sum() for a, b in complete])),
        "rewards": {},
    }  # fmt: skip
    tail = np.concatenate([np.arange(max(a, b - 499), b + 1) for (a, b), o in outcome.items()
                           if o == "timeout"] or [np.zeros(0, int)])  # fmt: skip
    if len(tail):  # what the expert does in the last 500 steps of its timeouts
        o, acts = data["obs"][tail], data["action"][tail]
        out["timeout_tail"] = {
            "steps": len(tail), "y_mean": float(o[:, 1].mean()),
            "speed_mean": float(np.hypot(o[:, 2], o[:, 3]).mean()),
            "angle_abs_mean": float(np.abs(o[:, 4]).mean()),
            "any_leg_contact": float(((o[:, 6] > 0) | (o[:, 7] > 0)).mean()),
            "action_share": [float(x) for x in np.bincount(acts, minlength=4) / len(acts)],
        }  # fmt: skip
    for name, fn in rewards.items():
        f = np.asarray(fn(np.array(data["obs"]), np.array(data["action"])), np.float64)
        sums = [f[a : b + 1].sum() for a, b in complete]
        disc = [discounted(f[a : b + 1]) for a, b in complete]
        term = {k: float(np.mean([f[b] for (a, b), o in outcome.items() if o == k]))
                for k in out["outcomes"]}  # fmt: skip
        rng = np.random.default_rng(RANDOM_SEED)
        other = (data["action"] + rng.integers(1, 4, len(f))) % 4  # any action but the expert's
        f_other = np.asarray(fn(np.array(data["obs"]), other), np.float64)
        out["rewards"][name] = {
            "mean_f_per_step": float(f.mean()),
            "frac_steps_positive": float((f > 0).mean()),
            "episode_sum": float(np.mean(sums)),
            "discounted_sum": float(np.mean(disc)),
            "terminal_f_by_outcome": term,
            "episode_sum_by_outcome": {
                k: float(np.mean([f[a : b + 1].sum() for (a, b), o in outcome.items() if o == k]))
                for k in out["outcomes"]
            },
            "mean_f_other_action": float(f_other.mean()),
            "pearson_f_true_step": float(np.corrcoef(f, data["reward"])[0, 1]),
        }
    return out


# --------------------------------------------------------------------------- PPO probe


def gae(rew, val, done_after, last_value, gamma, lam):
    """SB3's GAE on one env: ``done_after[t]``: the episode ended after step t (terminated;
    truncations bootstrapped into the reward before)."""
    adv = np.zeros_like(rew)
    last = 0.0
    for t in reversed(range(len(rew))):
        nxt = last_value if t == len(rew) - 1 else val[t + 1]
        nonterm = 1.0 - done_after[t]
        delta = rew[t] + gamma * nxt * nonterm - val[t]
        last = delta + gamma * lam * nonterm * last
        adv[t] = last
    return adv


def rollout(policy, fn, seed: int, scale: float = 1.0) -> dict[str, np.ndarray]:
    """One PPO rollout (n_steps, sampled actions, one env) on reward ``fn`` (None: the env
    reward) times ``scale``; returns, advantages as PPO's RolloutBuffer computes them."""
    torch.manual_seed(seed)
    env = make_env(ENV)
    obs, _ = env.reset(seed=seed)
    obs_l, act_l, rew_l, val_l, done_l = [], [], [], [], []
    for _ in range(PPO.n_steps):
        with torch.no_grad():
            action, value, _ = policy(torch.as_tensor(obs[None], dtype=torch.float32))
        a = int(action[0])
        nxt, r, term, trunc, _ = env.step(a)
        if fn is not None:
            r = float(fn(np.asarray(obs, np.float32)[None], np.array([a]))[0])
        r *= scale
        if trunc and not term:  # SB3's timeout bootstrap
            with torch.no_grad():
                r += GAMMA * float(
                    policy.predict_values(torch.as_tensor(nxt[None], dtype=torch.float32))[0, 0]
                )
        obs_l.append(np.asarray(obs, np.float32))
        act_l.append(a)
        rew_l.append(r)
        val_l.append(float(value[0, 0]))
        done_l.append(float(term or trunc))
        obs = nxt
        if term or trunc:
            obs, _ = env.reset(seed=seed + 1 + len(obs_l))
    with torch.no_grad():
        last_v = float(policy.predict_values(torch.as_tensor(obs[None], dtype=torch.float32))[0, 0])
    env.close()
    rew, val = np.asarray(rew_l, np.float32), np.asarray(val_l, np.float32)
    adv = gae(rew, val, np.asarray(done_l, np.float32), last_v, GAMMA, PPO.gae_lambda)
    return {"obs": np.stack(obs_l), "actions": np.asarray(act_l), "rewards": rew, "values": val,
            "advantages": adv, "returns": adv + val}  # fmt: skip


def is_policy_param(name: str) -> bool:
    return name.startswith(("mlp_extractor.policy_net", "action_net"))


def grad_probe(policy, fn, seed: int, scale: float = 1.0) -> dict[str, float]:
    """The first epoch's minibatches (ratio 1) of one rollout: gradient norms of the policy
    term (clipped surrogate + entropy) and of ``vf_coef * value loss``, the clip factor
    (``max_grad_norm`` over both nets' gradient, as SB3), and the clipped policy gradient's
    per-element RMS against Adam's eps (1e-5): rms / (rms + eps) is roughly the fraction of
    the nominal step size Adam can take with it (medians over the minibatches)."""
    b = rollout(policy, fn, seed, scale)
    named = [(n, p) for n, p in policy.named_parameters() if p.requires_grad]
    n_pi = sum(p.numel() for n, p in named if is_policy_param(n))
    perm = np.random.default_rng(seed).permutation(len(b["rewards"]))
    rows: list[tuple[float, float, float]] = []
    for start in range(0, len(perm), PPO.batch_size):
        idx = perm[start : start + PPO.batch_size]
        adv = torch.as_tensor(b["advantages"][idx])
        adv = (adv - adv.mean()) / (adv.std() + 1e-8)
        values, logp, entropy = policy.evaluate_actions(
            torch.as_tensor(b["obs"][idx]), torch.as_tensor(b["actions"][idx])
        )
        pg = -(adv * torch.exp(logp - logp.detach())).mean() - PPO.ent_coef * entropy.mean()
        vloss = PPO.vf_coef * ((torch.as_tensor(b["returns"][idx]) - values.flatten()) ** 2).mean()
        policy.zero_grad()
        (pg + vloss).backward()
        sq_pi = sum(float((p.grad**2).sum()) for n, p in named if is_policy_param(n))
        sq_v = sum(float((p.grad**2).sum()) for n, p in named if not is_policy_param(n))
        rows.append((sq_pi**0.5, sq_v**0.5, float(vloss.detach()) / PPO.vf_coef))
    policy.zero_grad()
    g_pi, g_v, vl = (np.array(c) for c in zip(*rows, strict=True))
    clip = np.minimum(1.0, PPO.max_grad_norm / (np.hypot(g_pi, g_v) + 1e-6))
    rms = g_pi * clip / np.sqrt(n_pi)
    return {
        "reward_per_step_mean": float(b["rewards"].mean()),
        "reward_per_step_std": float(b["rewards"].std()),
        "return_target_abs_mean": float(np.abs(b["returns"]).mean()),
        "value_abs_mean": float(np.abs(b["values"]).mean()),
        "value_loss": float(np.median(vl)),
        "grad_norm_policy": float(np.median(g_pi)), "grad_norm_value": float(np.median(g_v)),
        "clip_factor": float(np.median(clip)),
        "policy_grad_after_clip": float(np.median(g_pi * clip)),
        "policy_grad_rms_after_clip": float(np.median(rms)),
        "adam_step_fraction": float(np.median(rms / (rms + ADAM_EPS))),
    }  # fmt: skip


def update_probe(
    state: dict | None, fn, seed: int, states: np.ndarray, scale: float = 1.0
) -> dict[str, float]:
    """One real PPO iteration with SB3 (the study's settings and architecture; a fresh Adam):
    a 960-step rollout, 20 epochs; how far the policy moved on ``states``: mean KL(old || new)
    of the action distribution and the fraction of greedy actions that changed. ``state``
    None: a fresh policy (seeded)."""
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env import DummyVecEnv

    from pokerirl.gym.expert_policies import make_model
    from pokerirl.gym.rewards import learned_reward_env

    venv: Any = DummyVecEnv([lambda: Monitor(make_env(ENV))])
    if fn is not None:
        venv = learned_reward_env(venv, lambda o, a: scale * np.asarray(fn(o, a)))
    model = make_model(ENV, TASKS[ENV].rl, seed=seed, env=venv)
    if state is not None:
        model.policy.load_state_dict(state)
    x = torch.as_tensor(states)

    def probs() -> torch.Tensor:
        with torch.no_grad():
            return model.policy.get_distribution(x).distribution.probs.clone()

    before = probs()
    model.learn(total_timesteps=PPO.n_steps)
    after = probs()
    venv.close()
    kl = (before * (torch.log(before + 1e-12) - torch.log(after + 1e-12))).sum(1)
    return {
        "kl_mean": float(kl.mean()),
        "greedy_changed": float((before.argmax(1) != after.argmax(1)).float().mean()),
    }


def extrapolation_probe(fn, states: np.ndarray, expert_mean: float) -> dict[str, Any]:
    """f on off-data states (all four actions): how often and how much it pays more than the
    expert's mean f per step, and which action its argmax picks."""
    n = len(states)
    f = np.stack([np.asarray(fn(states, np.full(n, a)), np.float64) for a in range(4)], 1)
    return {
        "frac_pairs_above_expert_mean": float((f > expert_mean).mean()),
        "frac_states_best_above_expert_mean": float((f.max(1) > expert_mean).mean()),
        "f_p99": float(np.quantile(f, 0.99)), "f_max": float(f.max()),
        "argmax_action_share": [float(x) for x in np.bincount(f.argmax(1), minlength=4) / n],
    }  # fmt: skip


# --------------------------------------------------------------------------- tables


def fmt(x: float, d: int = 1) -> str:
    return f"{x:.{d}f}"


def table(headers: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def behaviour_summary(episodes: list[dict]) -> dict[str, Any]:
    lengths = np.array([len(e["actions"]) for e in episodes])
    returns = np.array([e["rewards"].sum() for e in episodes])
    finals = np.stack([e["final"] for e in episodes])
    outcomes: dict[str, int] = {}
    for e in episodes:
        outcomes[e["outcome"]] = outcomes.get(e["outcome"], 0) + 1
    return {
        "return_mean": float(returns.mean()), "return_std": float(returns.std()),
        "length_mean": float(lengths.mean()), "length_min": int(lengths.min()),
        "length_max": int(lengths.max()), "outcomes": outcomes,
        "on_pad": int(sum(e["on_pad"] for e in episodes)),
        "final_x_abs": float(np.abs(finals[:, 0]).mean()), "final_y": float(finals[:, 1].mean()),
        "final_speed": float(np.hypot(finals[:, 2], finals[:, 3]).mean()),
        "final_vy": float(finals[:, 3].mean()),
        "final_angle_abs": float(np.abs(finals[:, 4]).mean()),
        "main_per_episode": float(np.mean([e["main"] for e in episodes])),
        "side_per_episode": float(np.mean([e["side"] for e in episodes])),
        "main_fraction": float(np.sum([e["main"] for e in episodes]) / lengths.sum()),
    }  # fmt: skip


def outcome_text(o: dict[str, int]) -> str:
    short = {"landed": "L", "crashed": "C", "out_of_bounds": "O", "timeout": "T"}
    return " ".join(f"{short[k]}{o[k]}" for k in short if k in o)


def figure(results: dict[str, Any], path: Path) -> None:
    """f along time, per reward net: the expert's, the hover's, free fall's and the PPO run
    trained on that net (mean over the 20 episodes while >= 3 are alive)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(15, 8), sharex=True, sharey=True)
    for row, algo in enumerate(ALGOS):
        for k in RUNS:
            ax = axes[row, k]
            rname = f"{algo}/run-{k}"
            for label, source in (
                ("expert (lands)", "expert"),
                ("hover (timeout)", "hover"),
                ("do-nothing (crash)", "noop"),
                (f"PPO rl/{algo}/run-{k}", f"rl/{algo}/run-{k}"),
            ):
                curves = results["scores"][source][rname]["_per_episode_f"]
                T = max(len(c) for c in curves)
                grid = np.full((len(curves), T), np.nan)
                for i, c in enumerate(curves):
                    grid[i, : len(c)] = c
                alive = (~np.isnan(grid)).sum(0)
                keep = alive >= 3
                mean = np.nansum(grid[:, keep], 0) / alive[keep]
                ax.plot(np.flatnonzero(keep), mean, label=label, lw=1.2)
            ax.set_yscale("symlog", linthresh=1.0)
            ax.axhline(0, color="k", lw=0.5)
            name = "AIRL" if algo == "airl" else "H-AIRL"
            ax.set_title(f"{name} reward irl/{algo}/run-{k}", fontsize=10)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
            if row == 1:
                ax.set_xlabel("step t")
            if k == 0:
                ax.set_ylabel("f(s_t, a_t) (symlog), mean over episodes alive")
    fig.suptitle("What each learned reward pays along time (20 episodes, seeds 2,000,000+i)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def render(
    results: dict[str, Any],
    data: dict[str, Any],
    extrapolation: dict[str, Any],
    probe: dict[str, Any],
    n_off: int,
    expert_is_data_expert: bool,
) -> str:
    """The printed tables (diagnosis.txt)."""
    out_lines: list[str] = []
    say = out_lines.append
    say(f"expert = the data's expert (sha256 match): {expert_is_data_expert}")
    say(
        f"\n## 1. Behaviour: {EPISODES} deterministic episodes each, seeds "
        f"{EVAL_SEED}..{EVAL_SEED + EPISODES - 1} (outcomes: L landed at rest, C crashed, "
        "O out of bounds, T 1000-step timeout)\n"
    )
    rows = []
    for name, s in results["behaviour"].items():
        rows.append([name, fmt(s["return_mean"]) + " ± " + fmt(s["return_std"]),
                     fmt(s["study_final"]) if "study_final" in s else "",
                     f"{fmt(s['length_mean'], 0)} [{s['length_min']}, {s['length_max']}]",
                     outcome_text(s["outcomes"]), str(s["on_pad"]), fmt(s["final_x_abs"], 2),
                     fmt(s["final_y"], 2), fmt(s["final_vy"], 2), fmt(s["final_angle_abs"], 2),
                     fmt(s["main_per_episode"], 0), fmt(s["side_per_episode"], 0),
                     fmt(s["main_fraction"], 2)])  # fmt: skip
    say(table(["policy", "true return", "study's", "length [min, max]", "outcomes", "on pad",
               "|x| end", "y end", "vy end", "|angle| end", "main/ep", "side/ep",
               "main frac"], rows))  # fmt: skip

    say(
        f"\n## 2a. Expert data ({data['episodes']} complete episodes, mean length "
        f"{fmt(data['length_mean'], 0)}, outcomes {data['outcomes']}, true return "
        f"{fmt(data['true_return_mean'])}; its timeouts' last 500 steps: "
        f"{json.dumps(data.get('timeout_tail'))})\n"
    )
    rows = [[r, fmt(v["mean_f_per_step"], 2), fmt(v["frac_steps_positive"], 2),
             fmt(v["episode_sum"]), fmt(v["discounted_sum"]),
             ", ".join(f"{k} {fmt(x, 2)}" for k, x in v["terminal_f_by_outcome"].items()),
             ", ".join(f"{k} {fmt(x, 0)}" for k, x in v["episode_sum_by_outcome"].items()),
             fmt(v["mean_f_other_action"], 1), fmt(v["pearson_f_true_step"], 2)]
            for r, v in data["rewards"].items()]  # fmt: skip
    say(
        table(
            [
                "reward",
                "mean f/step",
                "frac f>0",
                "sum f/episode",
                "disc. sum (γ .999)",
                "terminal f",
                "sum f/episode by outcome",
                "mean f, other actions",
                "pearson(f, r_env)",
            ],
            rows,
        )
    )

    say(
        "\n## 2b. What each reward pays along the played episodes (mean over the 3 reward nets "
        "of a kind; per net in diagnosis.json). 'own PPO' = rl/<kind>/run-k scored by "
        "irl/<kind>/run-k\n"
    )
    names = ["expert", "heuristic", "hover", "noop", "random"]
    for algo in ALGOS:
        rows = []
        for name in [*names, "own PPO", *[f"rl/{r}/run-{k}" for r in RL_REWARDS for k in RUNS]]:
            per = [results["scores"][f"rl/{algo}/run-{k}" if name == "own PPO" else name]
                   [f"{algo}/run-{k}"] for k in RUNS]  # fmt: skip
            m = lambda key, per=per: float(np.mean([p[key] for p in per]))  # noqa: E731
            length = (np.mean([results["behaviour"][f"rl/{algo}/run-{k}"]["length_mean"]
                               for k in RUNS]) if name == "own PPO"
                      else results["behaviour"][name]["length_mean"])  # fmt: skip
            terms: dict[str, list[float]] = {}
            for p in per:
                for k2, v in p["terminal_f_by_outcome"].items():
                    terms.setdefault(k2, []).append(v)
            rows.append([name, fmt(length, 0), fmt(m("mean_f_per_step"), 2),
                         fmt(m("frac_steps_positive"), 2), fmt(m("episode_sum")),
                         fmt(m("discounted_sum")), fmt(m("mean_f_last10"), 2),
                         ", ".join(f"{k2} {fmt(float(np.mean(v)), 1)}"
                                   for k2, v in terms.items()),
                         fmt(m("pearson_f_true_step"), 2)])  # fmt: skip
        say(f"\n### {algo}\n")
        say(
            table(
                [
                    "behaviour",
                    "length",
                    "mean f/step",
                    "frac f>0",
                    "sum f/ep",
                    "disc. sum",
                    "mean f last 10",
                    "terminal f",
                    "pearson(f, r_env)",
                ],
                rows,
            )
        )

    say(
        "\n## 2c. Per reward net: the PPO run trained on it against reference behaviours "
        "(sum of f per episode; γ-discounted sum in brackets; expert data = all its complete "
        "episodes)\n"
    )
    rows = []
    for algo in ALGOS:
        for k in RUNS:
            r = f"{algo}/run-{k}"
            own = results["scores"][f"rl/{algo}/run-{k}"][r]
            cell = lambda x: f"{fmt(x['episode_sum'], 0)} ({fmt(x['discounted_sum'], 0)})"  # noqa: E731
            rows.append([r, cell(own), fmt(own["mean_f_per_step"], 2),
                         ", ".join(f"{o} {fmt(v, 1)}"
                                   for o, v in own["terminal_f_by_outcome"].items()),
                         cell(data["rewards"][r]), fmt(data["rewards"][r]["mean_f_per_step"], 2),
                         cell(results["scores"]["hover"][r]),
                         cell(results["scores"]["noop"][r]),
                         cell(results["scores"]["random"][r])])  # fmt: skip
    say(
        table(
            [
                "reward net",
                "own PPO: sum f (disc.)",
                "own PPO f/step",
                "own PPO terminal f",
                "expert data: sum f (disc.)",
                "expert f/step",
                "hover 1000 steps",
                "do-nothing",
                "random",
            ],
            rows,
        )
    )

    say(
        f"\n## 2d. Extrapolation: f on {n_off} states visited by the non-expert behaviours "
        "(all four actions)\n"
    )
    rows = [[r, fmt(v["frac_pairs_above_expert_mean"], 3),
             fmt(v["frac_states_best_above_expert_mean"], 3), fmt(v["f_p99"], 1),
             fmt(v["f_max"], 1), " / ".join(fmt(x, 2) for x in v["argmax_action_share"])]
            for r, v in extrapolation.items()]  # fmt: skip
    say(
        table(
            [
                "reward net",
                "frac (s,a) with f > expert mean f",
                "frac s with max_a f > it",
                "f p99",
                "f max",
                "argmax share noop/left/main/right",
            ],
            rows,
        )
    )

    say(
        "\n## 3. PPO at the reward's scale. Gradient probe: one 960-step rollout, the first "
        "epoch's 15 minibatches (medians): ‖g_pi‖ (clipped surrogate + entropy), ‖g_V‖ "
        f"(vf_coef x value loss), the clip factor (max_grad_norm {PPO.max_grad_norm} over both), "
        "the clipped policy gradient's per-element RMS and rms/(rms + Adam eps 1e-5). Update "
        "probe: one real SB3 PPO iteration (960 steps, 20 epochs, fresh Adam): mean KL(old||new) "
        "and the share of greedy actions changed on 1000 expert + 1000 off-data states. "
        f"'x{SCALE:g}': the same reward times {SCALE:g}\n"
    )
    rows = []
    for key, v in probe.items():
        for stage, p in v.items():
            rows.append([key, stage, fmt(p["reward_per_step_mean"], 2),
                         fmt(p["return_target_abs_mean"], 0), fmt(p["value_abs_mean"], 0),
                         f"{p['value_loss']:.3g}", f"{p['grad_norm_policy']:.3g}",
                         f"{p['grad_norm_value']:.3g}", f"{p['clip_factor']:.3g}",
                         f"{p['policy_grad_rms_after_clip']:.2g}",
                         fmt(p["adam_step_fraction"], 3), f"{p['kl_mean']:.2g}",
                         fmt(p["greedy_changed"], 3)])  # fmt: skip
    say(
        table(
            [
                "reward/run",
                "policy",
                "r/step",
                "|return target|",
                "|V|",
                "value loss",
                "‖g_pi‖",
                "‖g_V‖",
                "clip factor",
                "rms g_pi clipped",
                "Adam step frac",
                "KL one update",
                "greedy changed",
            ],
            rows,
        )
    )
    return "\n".join(out_lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("study", type=Path)
    parser.add_argument("--out", type=Path, default=HERE)
    args = parser.parse_args(argv)
    study: Path = args.study
    torch.set_num_threads(1)
    torch.manual_seed(0)

    shipped = resolve_expert_dir("shipped", ENV) / "model.pt"
    unit = json.loads((study / "expert.unit.json").read_text())
    expert_is_data_expert = (hashlib.sha256(shipped.read_bytes()).hexdigest()
                             == unit["config"]["expert"]["model_sha256"])  # fmt: skip

    rewards = {f"{a}/run-{k}": load_reward(study / "irl" / a / f"run-{k}")
               for a in ALGOS for k in RUNS}  # fmt: skip
    played = behaviours(study)
    results: dict[str, Any] = {"behaviour": {}, "scores": {}}
    for name, b in played.items():
        results["behaviour"][name] = {
            **behaviour_summary(b["episodes"]),
            **{k: v for k, v in b.items() if k != "episodes"},
        }
        results["scores"][name] = {r: score(b["episodes"], fn) for r, fn in rewards.items()}
    data = expert_data_scores(study, rewards)

    # Off-data states: everything the non-expert behaviours visited (seeded sample).
    visited = np.concatenate([e["obs"] for name, b in played.items() if name != "expert"
                              for e in b["episodes"]])  # fmt: skip
    sample_rng = np.random.default_rng(GRAD_SEED)
    off = visited[sample_rng.choice(len(visited), min(20_000, len(visited)), replace=False)]
    extrapolation = {r: extrapolation_probe(fn, off, data["rewards"][r]["mean_f_per_step"])
                     for r, fn in rewards.items()}  # fmt: skip
    expert_states = read_transitions(study / "expert.parquet")["obs"]
    kl_states = np.concatenate([
        expert_states[sample_rng.choice(len(expert_states), 1000, replace=False)],
        off[:1000]]).astype(np.float32)  # fmt: skip

    # PPO probes: fresh policies (the study's architecture, seeded) and the final ones.
    probe: dict[str, Any] = {}
    for reward in RL_REWARDS:
        for k in RUNS:
            run = study / "rl" / reward / f"run-{k}"
            fn = None if reward == "env" else rewards[f"{reward}/run-{k}"]
            kwargs = json.loads((run / "config.json").read_text())["policy_kwargs"]
            final, _ = load_rl_policy(run)
            state = {n: t.clone() for n, t in final.state_dict().items()}
            seed = GRAD_SEED + k
            entry: dict[str, Any] = {}
            scales = (1.0,) if reward == "env" else (1.0, SCALE)
            for scale in scales:
                torch.manual_seed(seed)
                fresh = build_policy(ENV, "ppo", kwargs)
                tag = "" if scale == 1.0 else f" x{scale:g}"
                entry["fresh" + tag] = {
                    **grad_probe(fresh, fn, seed, scale),
                    **update_probe(None, fn, seed, kl_states, scale),
                }
            entry["final"] = {
                **grad_probe(final, fn, seed),
                **update_probe(state, fn, seed, kl_states),
            }
            probe[f"{reward}/run-{k}"] = entry
    text = render(results, data, extrapolation, probe, len(off), expert_is_data_expert)
    print(text)

    # ----------------------------------------------------------------- write
    def clean(obj):
        if isinstance(obj, dict):
            return {k: clean(v) for k, v in obj.items() if not str(k).startswith("_")}
        if isinstance(obj, list | tuple):
            return [clean(v) for v in obj]
        return obj

    record = {
        "study": str(study), "env": ENV, "episodes": EPISODES,
        "seeds": {"episodes": [EVAL_SEED, EVAL_SEED + EPISODES - 1], "random_policy": RANDOM_SEED,
                  "grad_probe": GRAD_SEED}, "gamma": GAMMA, "hover_y": HOVER_Y,
        "expert_is_data_expert": expert_is_data_expert,
        "behaviour": results["behaviour"], "scores": clean(results["scores"]),
        "expert_data": data, "extrapolation": extrapolation, "ppo_probe": probe,
    }  # fmt: skip
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "diagnosis.json").write_text(json.dumps(record, indent=1) + "\n")
    (args.out / "diagnosis.txt").write_text(text + "\n")
    figure(results, args.out / "diagnosis.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
