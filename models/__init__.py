"""Pinocchio-backed models of crocopy (imported as ``crocopy.models``)."""
