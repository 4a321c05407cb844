"""A twin built by hand, without training: fast fixtures for what takes a twin.

Its 'posterior' is a narrow cloud about chosen values (the glucose gain at the paper
preset's 11, every other parameter at its prior's median): what the studies read of a
twin (its scenario) without the cost of fitting one.
"""

from __future__ import annotations

import numpy as np

from nirglucose.twin import Twin
from nirglucose.twin.device import TwinDevice
from nirglucose.twin.parameters import fitted_parameters, held_parameters
from nirglucose.twin.twin import parameter_entry

#: Glucose gain of the hand twin's channels (the paper preset's). [-]
HAND_GAIN = 11.0


def hand_twin(wavelengths_nm=(850.0, 940.0), *, times: bool = False, seed: int = 0) -> Twin:
    """A twin of a 10-bit device with these LEDs, 25 people x 8 readings."""
    device = TwinDevice(tuple(wavelengths_nm), 10, False, False, ("age_yr", "skin_temp_c"),
                        times, 25, 8, 24.0 if times else 0.0)
    params = fitted_parameters(device)
    rng = np.random.default_rng(seed)
    centre = np.array([p.to_fit(HAND_GAIN) if p.kind == "glucose signal"
                       else np.mean(p.fit_bounds) for p in params], dtype=float)
    width = np.array([0.02 * (p.fit_bounds[1] - p.fit_bounds[0]) for p in params])
    z = centre + width * rng.standard_normal((200, len(params)))
    values = np.column_stack([p.from_fit(z[:, i]) for i, p in enumerate(params)])
    entries = [parameter_entry(p, z[:, i]) for i, p in enumerate(params)]
    entries += [parameter_entry(p, None) for p in held_parameters(device)]
    map_values = np.array([p.from_fit(c) for p, c in zip(params, centre, strict=True)])
    return Twin(device, entries, values, map_values, {"warnings": []})
