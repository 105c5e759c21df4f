"""The paper's Gymnasium study (``pokerirl gym study``) and its H-AIRL sweep (``gym sweep``).

- :mod:`~pokerirl.studies.gym.config`: the presets (``StudyPreset``) and the task list;
- :mod:`~pokerirl.studies.gym.units`: the store units (expert data, IRL, RL runs);
- :mod:`~pokerirl.studies.gym.pipeline`: :func:`run_gym_study`, the units run and read back;
- :mod:`~pokerirl.studies.gym.results`: a task's ``summary.json``, typed;
- :mod:`~pokerirl.studies.gym.report`: the summary read back and rendered as ``report.md``;
- :mod:`~pokerirl.studies.gym.figures`: Figures 1-4;
- :mod:`~pokerirl.studies.gym.sweep`: the H-AIRL ablations.

Nothing is imported here: ``pokerirl report`` reads a gym study through ``config``,
``results`` and ``report`` alone, without torch or Gymnasium.
"""
