"""Online IRL's generator loop vs SB3 PPO alone: env steps/s on the same env (issue 43).

    python benchmarks/online.py [--env MountainCar-v0 Pendulum-v1] [--rounds 5] [--steps 2048]

Per env, in this process, one thread, one after the other: SB3 PPO ``learn`` on the env's own
reward, and the online trainer (:class:`pokerirl.irl.online.OnlineTrainer` with
:class:`pokerirl.gym.online.PPOGenerator`: collect, discriminator pass, relabel, PPO update,
validation metrics; no env evaluation) for the same rounds x steps, with the same PPO model
(:func:`pokerirl.gym.online.generator_model`) and seed. Prints each one's steps/s and the
ratio online / SB3: what the discriminator and the learned reward at every env step cost.
No target: the ratio is the price of online IRL over plain RL, to report.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import torch

from pokerirl.gym.collect import collect
from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir
from pokerirl.gym.irl import irl_config, load_env_transitions, obs_standardization, standardized
from pokerirl.gym.online import OnlineSettings, PPOGenerator, generator_model, vec_env
from pokerirl.gym.presets import TASKS
from pokerirl.irl.adversarial import default_nets
from pokerirl.irl.online import OnlineTrainer


def sb3_seconds(env_id: str, online: OnlineSettings, *, hidden: tuple[int, ...],
                activation: str) -> float:  # fmt: skip
    """SB3 PPO alone: ``rounds x generator_steps`` steps of ``learn`` on the env reward."""
    model = generator_model(env_id, vec_env(env_id, online, seed=0), settings=online, seed=0,
                            policy_hidden=hidden, activation=activation)  # fmt: skip
    start = time.perf_counter()
    model.learn(online.rounds * online.generator_steps)
    return time.perf_counter() - start


def online_seconds(env_id: str, online: OnlineSettings, data_path: Path, algo: str) -> float:
    """The online trainer's ``rounds`` rounds (the same PPO, plus the adversary)."""
    config = irl_config(algo, replace(TASKS[env_id].irl, epochs=1), seed=0)
    data = load_env_transitions(env_id, data_path)
    shift, scale = obs_standardization(data)
    data = standardized(data, shift, scale)
    reward, policy = default_nets(data, config, 0)
    generator = PPOGenerator(env_id=env_id, reward=reward, policy=policy,
                             config_activation=config.activation,
                             policy_hidden=tuple(config.policy_hidden), shift=shift, scale=scale,
                             settings=online, seed=0)  # fmt: skip
    trainer = OnlineTrainer(demonstrations=data, validation=data.subset(torch.arange(500)),
                            generator=generator, reward=reward, config=config,
                            generator_steps=online.generator_steps)  # fmt: skip
    start = time.perf_counter()
    trainer.train(online.rounds)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", nargs="+", default=["MountainCar-v0", "Pendulum-v1"])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=2048)
    parser.add_argument("--algo", default="airl")
    args = parser.parse_args()
    torch.set_num_threads(1)
    online = OnlineSettings(rounds=args.rounds, generator_steps=args.steps, envs=4)
    total = args.rounds * args.steps
    with tempfile.TemporaryDirectory() as folder:
        for env_id in args.env:
            data = Path(folder) / f"{env_id}.parquet"
            collect(load_expert(resolve_expert_dir("shipped", env_id)), data,
                    transitions=5000, seed=0)  # fmt: skip
            config = irl_config(args.algo, TASKS[env_id].irl, seed=0)
            sb3 = sb3_seconds(env_id, online, hidden=tuple(config.policy_hidden),
                              activation=config.activation)  # fmt: skip
            ours = online_seconds(env_id, online, data, args.algo)
            print(
                f"{env_id}: {total:,} env steps; SB3 PPO alone {total / sb3:,.0f} steps/s, "
                f"online {args.algo} {total / ours:,.0f} steps/s; ratio online / SB3 "
                f"{sb3 / ours:.2f}"
            )


if __name__ == "__main__":
    main()
