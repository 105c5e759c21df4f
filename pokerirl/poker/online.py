"""Online IRL on poker (``pokerirl train TABLE --mode online``): the IRL policy plays heads-up
hands on the vectorized engine against a fixed opponent, and the discriminator of
:class:`pokerirl.irl.online.OnlineTrainer` sees the states it reaches there, not the
expert's.

:class:`EngineGenerator` is the :class:`~pokerirl.irl.online.Generator`:

* ``collect(N)``: the run's :class:`~pokerirl.irl.nets.DiscretePolicy` (legal actions only)
  plays whole hands of :class:`~pokerirl.game.engine.LimitHoldemBatch`, alternating seats,
  against a built-in agent (:func:`pokerirl.game.bots.make_agent`: random by default),
  until it has taken N decisions; its rollout is those decisions in the run's encoding
  (obs, action, legal mask, the same player's next decision, done at its last one; a hand
  cut by the budget ends at the cut), with its log π of each action as drawn;
* ``learn``: a clipped PPO-style step over the rollout, the return of a decision being the
  sum of the hand's learned rewards from it on (γ = 1 within a hand) less their mean (the
  baseline), scaled by their std;
* ``imitate``: H-AIRL's cross-entropy step on expert (state, action) rows.

``log_prob`` and ``imitate`` take the rows' legal masks (the trainer passes the expert's and
the rollout's), so π is everywhere the masked distribution the policy draws from: the
discriminator scores expert and generator rows alike, as offline.

:func:`train_poker_online` writes the folder offline ``train`` writes (one run, or
``run-<k>`` and ``summary.json``), through :func:`~pokerirl.irl.run.begin_run` and
:func:`~pokerirl.irl.run.save_run`, each ``config.json`` recording ``data.mode = "online"``
and the generator's opponent and budget, so :func:`~pokerirl.irl.run.load_reward`, the
reward card and ``agent train --reward-run`` read it unchanged. Seeded: deals, the
opponent's numpy generator and the policy's torch generator all come from the run's seed.
"""

from __future__ import annotations

import functools
import json
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from enum import StrEnum
from pathlib import Path

import numpy as np
import torch
from torch import Tensor, nn

from pokerirl.atomic import write_text
from pokerirl.datasets.decisions import TABLE_ENCODING
from pokerirl.errors import ConfigError
from pokerirl.execution import progress_share
from pokerirl.game.bots import Agent, agent_actions, make_agent
from pokerirl.game.deals import deal_cards
from pokerirl.game.encodings import Encoding, get_encoding
from pokerirl.game.engine import LimitHoldemBatch
from pokerirl.game.match import agent_encoding, observe, turn_cards
from pokerirl.irl.config import AIRLConfig, Algo, IRLMode
from pokerirl.irl.metrics import Metric
from pokerirl.irl.nets import DiscretePolicy
from pokerirl.irl.online import Rollout, train_online_run
from pokerirl.irl.plots import plot_bands, plot_curves
from pokerirl.irl.records import EpochMetrics
from pokerirl.irl.run import (
    BASELINE_SHARE,
    SUMMARY_FILE,
    RunResult,
    RunSummary,
    data_record,
    drawn_baselines,
    run_baselines,
    save_run,
    summarize,
)
from pokerirl.irl.transitions import Transitions
from pokerirl.poker.data import read_table
from pokerirl.poker.train import (
    check_destination,
    warn_below_bc,
    write_reward_card,
)
from pokerirl.store import staged_folder

NUM_ACTIONS = 4  # call, raise, fold, check
DEAL_STREAM = 0  # spawn-key words of the run's seed: the deals, the opponent's draws
OPPONENT_STREAM = 1


class Opponent(StrEnum):
    """The fixed opponents the generator can play (built-in agents of the engine)."""

    RANDOM = "random"
    CALL = "call"
    RAISE = "raise"
    TIGHT = "tight"  # the synthetic months' bots, with their noise: TightBot, LooseBot
    LOOSE = "loose"

    def agent(self) -> Agent:
        return make_agent(
            f"{self.value}bot" if self in (Opponent.TIGHT, Opponent.LOOSE) else self.value
        )


class Returns(StrEnum):
    """What the generator's PPO step credits a decision with: ``hand``, the sum of the hand's
    learned rewards from it on (γ = 1); ``decision``, its own f(s, a) alone (the offline
    policy step's per-state objective, blind to how long a hand lasts)."""

    HAND = "hand"
    DECISION = "decision"


@dataclass(frozen=True, kw_only=True)
class PokerOnlineSettings:
    """The generator's budget and update: ``rounds`` of ``generator_steps`` decisions against
    ``opponent``; each round ``ppo_epochs`` full-batch PPO steps clipped at ``clip``."""

    rounds: int = 20
    generator_steps: int = 2048
    opponent: str = Opponent.RANDOM
    ppo_epochs: int = 4
    clip: float = 0.2
    returns: str = Returns.HAND

    def __post_init__(self) -> None:
        if self.rounds < 1 or self.generator_steps < 1 or self.ppo_epochs < 1:
            raise ConfigError("online IRL needs at least 1 round, 1 generator step, 1 PPO epoch")
        if self.opponent not in tuple(Opponent):
            raise ConfigError(f"unknown opponent {self.opponent!r} (known: {', '.join(Opponent)})")
        if self.returns not in tuple(Returns):
            raise ConfigError(f"unknown returns {self.returns!r} (known: {', '.join(Returns)})")
        if not 0 < self.clip < 1:
            raise ConfigError(f"the PPO clip must lie in (0, 1), got {self.clip}")

    @classmethod
    def given(
        cls, *, rounds: int | None, generator_steps: int | None, opponent: str | None
    ) -> PokerOnlineSettings:
        """The defaults, each setting given (not None or 0) replacing its own: what ``train
        --mode online`` and a study's online IRL stage ask for."""
        found = cls()
        return cls(rounds=rounds or found.rounds, opponent=opponent or found.opponent,
                   generator_steps=generator_steps or found.generator_steps)  # fmt: skip

    def record(self) -> dict[str, object]:
        """What a run's ``config.json`` says of its generator."""
        return {"rounds": self.rounds, "generator_steps": self.generator_steps,
                "opponent": str(self.opponent), "ppo_epochs": self.ppo_epochs,
                "clip": self.clip, "returns": str(self.returns)}  # fmt: skip


def _stream(seed: int, word: int) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(word,))))


class EngineGenerator:
    """The IRL ``policy`` playing heads-up hands on the engine against ``settings.opponent``,
    its observations in ``encoding``: an online IRL :class:`~pokerirl.irl.online.Generator`."""

    def __init__(
        self,
        *,
        policy: DiscretePolicy,
        encoding: str | Encoding,
        settings: PokerOnlineSettings,
        lr: float,
        seed: int,
    ) -> None:
        self.policy, self.encoding, self.settings = policy, get_encoding(encoding), settings
        if policy.obs_dim != self.encoding.width or policy.action_dim != NUM_ACTIONS:
            raise ConfigError(
                f"the policy reads {policy.obs_dim} features and {policy.action_dim} actions; "
                f"{self.encoding.spec} has {self.encoding.width} and poker {NUM_ACTIONS}"
            )
        self.opponent = Opponent(settings.opponent).agent()
        self.opponent_encoding = agent_encoding(self.opponent)
        self.seed = int(seed)
        self.rng = _stream(seed, OPPONENT_STREAM)
        self.torch_rng = torch.Generator().manual_seed(seed)
        self.optimizer = torch.optim.Adam(policy.parameters(), lr=lr)
        self.dealt = 0  # deals of the seed used so far: every hand gets a fresh one
        self.payoffs = np.zeros(0)  # its net big blinds in each hand of the last collect

    # ------------------------------------------------------------------ playing

    def play(self, hands: int) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """``hands`` hands, the generator in seat ``hand % 2``: its decisions in play order
        (hand, obs, legal mask, action, masked log π) and its payoff per hand."""
        deals = deal_cards(seed=self.seed, start=self.dealt, count=hands)
        mine_seat = (self.dealt + np.arange(hands)) % 2  # alternate seats, as a match does
        first = self.dealt
        self.dealt += hands
        game = LimitHoldemBatch(deals=deals)
        parts: dict[str, list[np.ndarray]] = {k: [] for k in ("hand", "obs", "legal", "action",
                                                               "log_prob")}  # fmt: skip
        while (active := game.active()).size:
            mine = game.to_act[active] == mine_seat[active]
            ours, theirs = active[mine], active[~mine]
            if ours.size:
                obs = observe(game, ours, self.encoding)
                legal = game.legal_mask(ours)
                with torch.no_grad():
                    log_pi = self.policy(torch.as_tensor(obs, dtype=torch.float32),
                                         torch.as_tensor(legal))  # fmt: skip
                actions = torch.multinomial(log_pi.exp(), 1, generator=self.torch_rng)[:, 0]
                chosen = log_pi.gather(1, actions[:, None])[:, 0]
                for key, value in (
                    ("hand", first + ours),
                    ("obs", obs),
                    ("legal", legal),
                    ("action", actions.numpy()),
                    ("log_prob", chosen.numpy()),
                ):
                    parts[key].append(np.asarray(value))  # fmt: skip
                game.step(actions.numpy(), ours)
            if theirs.size:
                seen = observe(game, theirs, self.opponent_encoding)
                legal = game.legal_mask(theirs)
                cards = functools.partial(turn_cards, game, theirs)  # only if it sees them
                game.step(agent_actions(self.opponent, seen, legal, self.rng, cards), theirs)
        decisions = {k: np.concatenate(v) if v else np.empty(0) for k, v in parts.items()}
        return decisions, game.payoffs[np.arange(hands), mine_seat]

    def collect(self, steps: int) -> Rollout:
        """Whole hands until ``steps`` decisions of the generator, its rows hand by hand."""
        found: list[dict[str, np.ndarray]] = []
        payoffs: list[np.ndarray] = []
        taken = 0
        while taken < steps:
            # About two of its decisions a hand: ask for what is left, at least 16 hands.
            decisions, paid = self.play(max(16, (steps - taken) // 2 + 1))
            found.append(decisions)
            payoffs.append(paid)
            taken += len(decisions["action"])
        self.payoffs = np.concatenate(payoffs)
        rows = {k: np.concatenate([d[k] for d in found]) for k in found[0]}
        # A hand's decisions together, in play order; then the budget cuts the last hand only.
        order = np.argsort(rows["hand"], kind="stable")[:steps]
        rows = {k: v[order] for k, v in rows.items()}
        hand = rows["hand"]
        following = np.minimum(np.arange(steps) + 1, steps - 1)
        dones = np.append(hand[1:] != hand[:-1], True)  # its last decision, or the cut
        obs = torch.as_tensor(rows["obs"], dtype=torch.float32)
        next_obs = obs[torch.as_tensor(np.where(dones, np.arange(steps), following))]
        transitions = Transitions(
            obs=obs, actions=torch.as_tensor(rows["action"], dtype=torch.int64), groups=hand,
            next_obs=next_obs, dones=torch.as_tensor(dones),
            legal_mask=torch.as_tensor(rows["legal"], dtype=torch.bool), num_actions=NUM_ACTIONS,
        )  # fmt: skip
        log_probs = torch.as_tensor(rows["log_prob"], dtype=torch.float32)
        return Rollout(transitions=transitions, log_probs=log_probs)

    # ------------------------------------------------------------------ learning

    def log_prob(self, obs: Tensor, actions: Tensor, legal_mask: Tensor | None = None) -> Tensor:
        return (actions * self.policy(obs, legal_mask)).sum(-1)  # π over the legal actions

    def learn(self, rollout: Rollout, rewards: Tensor) -> Mapping[str, float]:
        data = rollout.transitions
        assert data.dones is not None and data.legal_mask is not None  # collect sets both
        by_hand = self.settings.returns == Returns.HAND
        advantages = standardized(hand_returns(rewards, data.dones) if by_hand else rewards)
        old = rollout.log_probs
        clip = self.settings.clip
        for _ in range(self.settings.ppo_epochs):
            log_pi = self.policy(data.obs, data.legal_mask)
            new = log_pi.gather(1, data.actions[:, None])[:, 0]
            ratio = torch.exp(new - old)
            loss = -torch.minimum(ratio * advantages,
                                  ratio.clamp(1 - clip, 1 + clip) * advantages).mean()  # fmt: skip
            self.optimizer.zero_grad()
            loss.backward()
            self.optimizer.step()
        with torch.no_grad():
            log_pi = self.policy(data.obs, data.legal_mask)
            entropy = -(log_pi.exp() * log_pi.clamp_min(-30)).sum(-1).mean()
        return {
            Metric.POLICY_LOSS: float(loss.detach()),
            "policy_entropy": float(entropy),
            "generator_bb_per_hand": float(self.payoffs.mean()) if self.payoffs.size else 0.0,
        }

    def imitate(
        self, obs: Tensor, actions: Tensor, *, weight: float, legal_mask: Tensor | None = None
    ) -> float:
        loss = -weight * self.log_prob(obs, actions, legal_mask).mean()
        self.optimizer.zero_grad()
        loss.backward()
        self.optimizer.step()
        return float(loss.detach())

    def policy_net(self) -> DiscretePolicy:
        return self.policy


def hand_returns(rewards: Tensor, dones: Tensor) -> Tensor:
    """Each row's sum of the rewards from it to its hand's end (γ = 1), rows of a hand
    contiguous and ``dones`` marking each hand's last.

    >>> hand_returns(torch.tensor([1.0, 2.0, 4.0]), torch.tensor([False, True, True])).tolist()
    [3.0, 2.0, 4.0]
    """
    returns = torch.empty_like(rewards)
    running = torch.zeros(())
    for t in range(len(rewards) - 1, -1, -1):  # rollouts are a few thousand rows: plain loop
        running = rewards[t] + (0.0 if bool(dones[t]) else running)
        returns[t] = running
    return returns


def standardized(values: Tensor) -> Tensor:
    """``values`` less their mean (REINFORCE's baseline), over their std when it is not 0."""
    centred = values - values.mean()
    std = centred.std() if len(values) > 1 else torch.zeros(())
    return centred / std if float(std) > 0 else centred


# --------------------------------------------------------------------------- the command


def train_poker_online(
    table: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    algo: str = Algo.HAIRL,
    runs: int = 1,
    config: AIRLConfig | None = None,
    settings: PokerOnlineSettings | None = None,
    encoding: Encoding | None = None,
    overwrite: bool = False,
    progress: bool = True,
    on_round: Callable[[int, EpochMetrics], None] | None = None,
) -> RunSummary:
    """``runs`` online runs of ``algo`` (seeds ``config.seed + k``, each its own split and
    baselines by its seed, as offline ``train --runs``) on the decision table ``table`` in
    ``encoding``, into ``out`` as offline ``train`` writes it (one run: ``out`` itself);
    ``on_round`` gets each run's index and round line."""
    if runs < 1:
        raise ConfigError(f"runs must be at least 1, got {runs}")
    config = config or AIRLConfig.for_algo(algo)
    settings = settings or PokerOnlineSettings()
    out = Path(out)
    check_destination(out, overwrite=overwrite)
    encoding = TABLE_ENCODING if encoding is None else encoding
    data = read_table(table, encoding=encoding)
    several = runs > 1
    results = []
    with staged_folder(out) as stage:  # the store's: a kill leaves out as it was
        for k in range(runs):
            folder = stage / f"run-{k}" if several else stage
            run_config = replace(config, seed=config.seed + k)
            # As offline train's runs: each its own split and baselines, by its own seed.
            train_data, val_data, val_groups = data.split(val_fraction=config.val_fraction,
                                                          seed=run_config.seed)  # fmt: skip
            with progress_share(k / runs, (k + BASELINE_SHARE) / runs):
                found = run_baselines(train_data, val_data, config=run_config, progress=progress)
            data_info = {
                **data_record(data, train_data, val_data, path=table),
                "encoding": encoding.spec,
                "mode": IRLMode.ONLINE.value,
                "generator": settings.record(),
            }
            def make_generator(
                reward: nn.Module, policy: nn.Module, seed: int = run_config.seed
            ) -> EngineGenerator:
                assert isinstance(policy, DiscretePolicy)  # a table's actions are discrete
                return EngineGenerator(policy=policy, encoding=encoding, settings=settings,
                                       lr=config.policy_lr, seed=seed)  # fmt: skip

            with progress_share((k + BASELINE_SHARE) / runs, (k + 1) / runs):
                result = train_online_run(
                    folder, demonstrations=train_data, validation=val_data,
                    val_groups=val_groups, baselines=found, config=run_config,
                    make_generator=make_generator, rounds=settings.rounds,
                    generator_steps=settings.generator_steps,
                    on_round=None if on_round is None else functools.partial(on_round, k),
                )  # fmt: skip
            save_run(result, folder, algo=algo, data=data_info, baselines=found)
            plot_curves(result.metrics, folder, baselines=drawn_baselines(found, data))
            write_reward_card(folder, table)
            results.append(
                RunResult(
                    out=str(out / folder.name) if several else str(out), seed=run_config.seed,
                    metrics=tuple(result.metrics), baselines=found,
                    samples_per_second=result.samples_per_second,
                    train_rows=len(train_data), val_rows=len(val_data),
                )
            )  # fmt: skip
        if several:
            summary = summarize(results).to_json()
            write_text(stage / SUMMARY_FILE, json.dumps(summary, indent=2) + "\n")
            plot_bands(summary, stage)
    for run in results:  # as offline: a reward below its own BC is flagged
        warn_below_bc(Path(run.out), run.metrics[-1], run.baselines)
    return RunSummary.of(results, out_dir=out, several=several)
