"""Train an SB3 agent on a learned reward (``pokerirl.learned_reward_env``).

Learns a reward from a few CartPole expert episodes with H-AIRL into a run folder, loads it
back with ``pokerirl.load_reward`` (any run folder of ``pokerirl gym train`` or ``train_into``
works, as does any callable ``reward(obs, actions) -> (n,) rewards``), and trains PPO on it.
The environment's own reward is never shown to PPO; Monitor still records it, so the true
return of the trained agent is what the result line reports.

    python docs/examples/learned_reward_sb3.py --episodes 10 --epochs 10 --steps 20000

Needs the ``pokerirl[gym]`` extra (Gymnasium, Stable-Baselines3). Prints one ``result:`` line.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import gymnasium as gym
import numpy as np
from stable_baselines3 import PPO
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv

import pokerirl


def expert_data(episodes: int, *, seed: int) -> pokerirl.Transitions:
    """CartPole episodes of a two-line controller, as Transitions (episode = group)."""
    env = gym.make("CartPole-v1")
    columns: dict[str, list] = {"obs": [], "acts": [], "next_obs": [], "dones": [], "episode": []}
    for episode in range(episodes):
        obs, _ = env.reset(seed=seed + episode)
        done = False
        while not done:
            action = int(obs[2] + 0.5 * obs[3] > 0)  # push the way the pole falls
            next_obs, _, terminated, truncated, _ = env.step(action)
            done = terminated or truncated
            for name, value in (("obs", obs), ("acts", action), ("next_obs", next_obs),
                                ("dones", done), ("episode", episode)):  # fmt: skip
                columns[name].append(value)
            obs = next_obs
    env.close()
    return pokerirl.Transitions.from_arrays(
        np.array(columns["obs"]), np.array(columns["acts"]), groups=np.array(columns["episode"]),
        next_obs=np.array(columns["next_obs"]), dones=np.array(columns["dones"]), num_actions=2,
    )  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10, help="expert episodes")
    parser.add_argument("--epochs", type=int, default=10, help="reward-learning epochs")
    parser.add_argument("--steps", type=int, default=20_000, help="PPO timesteps")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    data = expert_data(args.episodes, seed=args.seed)
    with tempfile.TemporaryDirectory() as scratch:
        run = Path(scratch) / "run"
        config = pokerirl.AIRLConfig.for_algo("hairl", epochs=args.epochs, val_fraction=0.2,
                                              seed=args.seed)  # fmt: skip
        pokerirl.train_into(data, run, algo="hairl", config=config)
        learned = pokerirl.load_reward(run)  # g(s, a): learned(obs (n, 4), action ids (n,))

    # CartPole ends when the pole falls. Where the learned reward is negative, a shorter
    # episode earns more, and PPO learns to drop the pole (AIRL's survival bias in tasks
    # that end early: Kostrikov et al., 2019). A constant shift that makes the reward
    # non-negative on the expert's own decisions removes that pull (at the defaults: a true
    # return near 10 unshifted, above 100 shifted).
    floor = float(learned(data.obs.numpy(), data.actions.numpy()).min())

    def reward(obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        return learned(obs, actions) - floor

    # Monitor inside, the learned reward outside it: Monitor's episode returns stay the
    # environment's, which is how the agent is judged below.
    venv = DummyVecEnv([lambda: Monitor(gym.make("CartPole-v1"))])
    model = PPO("MlpPolicy", pokerirl.learned_reward_env(venv, reward), n_steps=256,
                batch_size=64, seed=args.seed, verbose=0)  # fmt: skip
    model.learn(total_timesteps=args.steps)
    true_return, _ = evaluate_policy(model, Monitor(gym.make("CartPole-v1")), n_eval_episodes=5)
    print(f"result: PPO on the learned reward, {args.steps} steps: true return "
          f"{true_return:.1f} (the expert's: 500, a random policy's: about 22)")


if __name__ == "__main__":
    main()
