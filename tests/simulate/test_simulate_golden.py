"""Same seed, same bytes across refactors: frame hashes recorded before issue 22's move.

The hashes were taken at main 2a4031c, before every scenario number moved into the
config and the per-LED values became one record per LED; the refactor must not change
a single byte of any preset's data (nor of a 3-LED device's). A change of physics that
is meant to change the data updates these hashes in the same commit, saying why.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from device_data import LED_SETS, device_overrides

#: (preset, overrides) -> SHA-256 of the frame (12 subjects x 3, seed 11).
GOLDEN = {
    "paper": "f0f48d3ee0187239253fe5f4f4afec1dd4a076e33493a4850ea5eb23ce4e306a",
    "wearable": "c6575aae0b213360d49ac9fe81cc3a602d61930428a951582ba6add64bbf87fb",
    "lab": "82d3aa904d4c96d33f2a0263097b032748ba5683931e4463076ea7223bd35835",
    "field": "bc616dee239df6e7111e3bf5ffe0029454df29ccd3c4c0dffc6dec67e6fc8ce6",
    "physical": "d2651cd5d0f198f53fdb0e0b10d38cf6f12e0b811042951b583ced29f6290605",
    "wearable-3led": "1cd0336097a68b97cd144e1475d00877fc3100fa32af7e4c3269e35cf0971260",
    "paper-3led": "33b00e76b37ab00ce696fbe569a4d7be2f80b1f4784e6cbd2b553097fc5a1cb5",
}


def frame_hash(frame: pd.DataFrame) -> str:
    """SHA-256 over every column's name, dtype and raw bytes (categories by code)."""
    h = hashlib.sha256()
    for c in frame.columns:
        s = frame[c]
        h.update(c.encode())
        h.update(str(s.dtype).encode())
        if isinstance(s.dtype, pd.CategoricalDtype):
            h.update("|".join(map(str, s.cat.categories)).encode())
            h.update(np.ascontiguousarray(s.cat.codes.to_numpy()).tobytes())
        else:
            h.update(np.ascontiguousarray(s.to_numpy()).tobytes())
    return h.hexdigest()


@pytest.mark.parametrize("name", list(GOLDEN))
def test_frames_byte_identical_to_recorded(name):
    preset, _, device = name.partition("-")
    overrides = device_overrides(LED_SETS[3], 14) if device == "3led" else None
    frame = ng.simulate(preset, 12, 3, 11, overrides=overrides).frame
    assert frame_hash(frame) == GOLDEN[name]


def test_hash_sees_a_one_ulp_change():
    frame = ng.simulate("lab", 2, 2, 0).frame
    moved = frame.copy()
    moved.loc[0, "glucose_mgdl"] = np.nextafter(moved.loc[0, "glucose_mgdl"], np.inf)
    assert frame_hash(moved) != frame_hash(frame)
