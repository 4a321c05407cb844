"""
A small noise sweep
===================

``noise_scale`` multiplies every noise source of the scenario at once (each source also
has its own switch and scale). Here the same cohort is simulated at four scales and one
estimator is fitted and scored at each; ``nirglucose sweep`` does this over seeds and
models with repeated grouped folds, locally or on a Dask cluster.
"""

import matplotlib.pyplot as plt

import nirglucose as ng
from nirglucose.metrics import rmse
from nirglucose.models import make_model

scales = [0.5, 1.0, 2.0, 4.0]
errors = []
for scale in scales:
    frame = ng.simulate(preset="paper", n_subjects=30, per_subject=3, seed=0,
                        overrides={"noise_scale": scale}).frame
    train, test = frame[frame["subject_id"] < 20], frame[frame["subject_id"] >= 20]
    pred = make_model("device-inversion").fit(train).predict(test)
    errors.append(rmse(test["glucose_mgdl"], pred))
    print(f"noise_scale {scale:5.2f}: RMSE {errors[-1]:5.1f} mg/dL")

# %%
# Error against the noise scale (one seed, one split: a sketch, not a result).
fig, ax = plt.subplots(figsize=(5, 3.5), layout="constrained")
ax.plot(scales, errors, marker="o")
ax.set(xscale="log", xlabel="noise_scale [-]", ylabel="RMSE [mg/dL]",
       title="device-inversion, paper preset")
plt.show()
