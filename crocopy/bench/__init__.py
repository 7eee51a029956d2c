"""``crocopy.bench``: the benchmarks behind ``crocopy bench`` (crocopy alone, or side by side with
Crocoddyl when the ``bench`` extra is installed). Not imported by the library."""
