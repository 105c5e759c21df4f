"""Hand-history readers: the IRC Poker Database's files (:mod:`pokerirl.parsers.irc`) and the
replay of a heads-up hand's action strings into decisions (:mod:`pokerirl.parsers.replay`).
Nothing is re-exported: import from the module."""
