"""The studies: each one declares its stages as units of :mod:`pokerirl.store` and reads their
outputs back into a report.

- :mod:`pokerirl.studies.poker`: the paper's poker study (``pokerirl study``) and the transfer
  test (``pokerirl transfer``);
- :mod:`pokerirl.studies.gym`: the Gymnasium study (``pokerirl gym study``) and the H-AIRL
  ablations (``pokerirl gym sweep``);
- :mod:`pokerirl.studies.demo`: both quick studies on built-in data (``pokerirl demo``).

Nothing is imported here: ``pokerirl report`` reads a poker study without loading the gym.
"""
