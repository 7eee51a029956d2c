"""The census of bad inputs (``census.py``, issue 27) meets the bar: every bad value refused with an error that
names its argument (at most a few unclear ones), no NaN/inf returned without a warning, no crash, no hang."""

from __future__ import annotations

import collections

import census


def test_census_of_bad_inputs_meets_the_bar():
    rows = census.run()
    counts = collections.Counter(row[4] for row in rows)
    offenders = [f"{row[4]}: {row[1]}({row[2]}={row[3]}) {row[5]}" for row in rows if row[4] not in ("clear", "ok")
                 and row[4] != "warned-nonfinite"]
    assert len(rows) > 2000 and counts["clear"] > 1800
    assert counts["crash"] == counts["hang"] == counts["silent-nonfinite"] == counts["accepted"] == 0, offenders
    assert counts["unclear"] <= 5, offenders
    assert all(row[4] != "unclear" or row[1] == "ContactModel2D" for row in rows), offenders  # nu/gains overload
