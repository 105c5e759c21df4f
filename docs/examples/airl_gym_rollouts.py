"""AIRL / H-AIRL on your own Gymnasium rollouts.

Roll out any policy you have (here a two-line CartPole controller stands in for your expert),
keep each episode in the ``imitation`` library's trajectory layout (``obs`` T + 1 rows,
``acts`` T, ``terminal``, ``rews``), turn the episodes into pokerirl's ``Transitions`` and
train a reward and a policy on them.

    python docs/examples/airl_gym_rollouts.py --episodes 20 --epochs 40 --algo hairl

Needs the ``pokerirl[gym]`` extra (Gymnasium). Prints one ``result:`` line.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import pokerirl


def expert(obs: np.ndarray) -> int:
    """Your expert: push the cart the way the pole is falling (angle plus angular speed)."""
    return int(obs[2] + 0.5 * obs[3] > 0)


def rollouts(episodes: int, *, seed: int) -> list[dict]:
    """One dict per episode with imitation's trajectory fields (any such objects will do:
    imitation's own ``TrajectoryWithRew`` too)."""
    env = gym.make("CartPole-v1")
    found = []
    for episode in range(episodes):
        obs, _ = env.reset(seed=seed + episode)
        states, actions, rewards = [obs], [], []
        terminated = truncated = False
        while not (terminated or truncated):
            action = expert(obs)
            obs, reward, terminated, truncated, _ = env.step(action)
            states.append(obs)
            actions.append(action)
            rewards.append(reward)
        # terminal: the episode really ended (False when a time limit cut it off).
        found.append({"obs": np.array(states), "acts": np.array(actions),
                      "rews": np.array(rewards), "terminal": terminated})  # fmt: skip
    env.close()
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=20, help="expert episodes to roll out")
    parser.add_argument("--epochs", type=int, default=40, help="training epochs")
    parser.add_argument("--algo", choices=["airl", "hairl"], default="hairl")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    # Episode i becomes group i: the train/validation split never cuts an episode.
    data = pokerirl.from_imitation_trajectories(rollouts(args.episodes, seed=args.seed),
                                                num_actions=2)  # fmt: skip
    # The paper's settings for the algorithm (AIRL: no supervised term, no noise), resized.
    config = pokerirl.AIRLConfig.for_algo(args.algo, epochs=args.epochs, val_fraction=0.2,
                                          seed=args.seed)  # fmt: skip
    train, val, _ = data.split(val_fraction=config.val_fraction, seed=config.seed)
    result = pokerirl.train(train, val, config=config, progress=False)

    last = result.metrics[-1]
    # val_alignment: how often the learned policy's argmax picks the expert's action on the
    # held-out episodes; val_reward_alignment: the same for the reward's argmax.
    print(f"result: {args.algo} on {len(data)} transitions from {args.episodes} episodes, "
          f"{args.epochs} epochs: policy alignment {last['val_alignment']:.3f}, "
          f"reward alignment {last['val_reward_alignment']:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
