"""Ready problem builders for the papers' benchmarks (imported as ``crocopy.problems``)."""
