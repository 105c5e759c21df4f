"""Poker data sets: named IRC data and its cache (:mod:`~pokerirl.datasets.catalog`),
``pokerirl ingest`` (:mod:`~pokerirl.datasets.ingest`; which players and period it keeps,
:mod:`~pokerirl.datasets.players`; the rows it writes, :mod:`~pokerirl.datasets.table`),
reading a decision table back (:mod:`~pokerirl.datasets.decisions`) and a toy table with a known
rule (:mod:`~pokerirl.datasets.toy`). Nothing is re-exported: import from the module."""
