"""crocopy's per-user cache folder (compiled kernels when the install is read-only, parsed robot models).

``$CROCOPY_CACHE_DIR`` when set, else ``$XDG_CACHE_HOME/crocopy``, else ``~/.cache/crocopy``.
Nothing in it is needed: deleting it only makes the next run rebuild what it held.
"""

from __future__ import annotations

import os
from pathlib import Path


def user_cache_dir(*parts: str) -> Path:
    """The cache folder ``<base>/crocopy/<parts...>`` (see the module docstring); not created here."""
    base = os.environ.get("CROCOPY_CACHE_DIR")
    if not base:
        xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        base = os.path.join(xdg, "crocopy")
    return Path(base, *parts)
