"""``crocopy.experiments``: the papers' experiments behind ``crocopy paper`` and ``crocopy table1``.
Not imported by the library."""
