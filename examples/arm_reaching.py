"""Kinova arm reaching a point in 1 s with FDDP; writes ``arm.html``."""

from crocopy.cli import main

main(["solve", "arm", "--solver", "fddp"])
