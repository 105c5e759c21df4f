"""A pokerirl agent inside RLCard 1.2.0 (``pokerirl.RLCardAgent``).

Any agent pokerirl can play (a built-in bot, an agent folder of ``pokerirl agent train``,
``reward:RUN``, your own class: see own_poker_agent.py) gets RLCard's agent interface
(``use_raw``, ``step``, ``eval_step``) and plays in ``rlcard.make("limit-holdem")``, here in
RLCard's own ``tournament`` against RLCard's ``RandomAgent``.

    python docs/examples/agent_in_rlcard.py --agent tightbot --hands 10000

Prints one ``result:`` line: the agent's mean payoff in big blinds per hand, as RLCard counts it.
"""

from __future__ import annotations

import argparse

import rlcard
from rlcard.agents import RandomAgent  # importing rlcard.agents runs `pip freeze` (seconds)
from rlcard.utils import set_seed, tournament

import pokerirl


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agent", default="tightbot", help="what pokerirl.resolve_agent takes")
    parser.add_argument("--hands", type=int, default=10_000, help="hands of the tournament")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    set_seed(args.seed)  # RLCard's RandomAgent draws from numpy's global generator
    env = rlcard.make("limit-holdem", config={"seed": args.seed})
    # seed: the generator the pokerirl agent draws its own random choices from.
    ours = pokerirl.RLCardAgent(agent=pokerirl.resolve_agent(args.agent), seed=args.seed)
    env.set_agents([ours, RandomAgent(num_actions=env.num_actions)])
    payoffs = tournament(env, args.hands)
    print(f"result: {ours.name} vs RLCard's RandomAgent in RLCard, {args.hands} hands: "
          f"{payoffs[0]:+.3f} big blinds per hand")


if __name__ == "__main__":
    main()
