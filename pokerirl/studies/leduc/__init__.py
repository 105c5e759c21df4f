"""The Leduc study (``pokerirl leduc study``): IRL from a CFR+ expert, measured exactly.

:mod:`~.learn` trains and reads back the learners, :mod:`~.study` runs the stages and
writes the report. Nothing is imported here: the command line loads it lazily.
"""
