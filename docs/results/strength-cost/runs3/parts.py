"""Where a 20,000-hand DQN run's CPU goes (seed 0, own play, turn table on): time.process_time
around the learner's updates, its decisions and the strength encoding. Output: parts.txt."""
import pokerirl.agents.dqn as D
import pokerirl.game.encodings as E
from _timing import acc, runs, wrap
from pokerirl.game.equity import use_turn_table

use_turn_table(True)
wrap(D.DQNLearner, "update", "update")
wrap(E.StrengthEncoding, "encode", "encode")
wrap(D, "_learner_decides", "decides")
wrap(D, "_close_ended", "close_ended")
for enc, tot, l in runs(["rlcard", "strength"] * 2):
    print(enc, f"total {tot:.3f}", {k: round(v, 3) for k, v in acc.items()}, "rest",
          round(tot - acc["update"] - acc["decides"], 3), l.total_t, l.train_t)
