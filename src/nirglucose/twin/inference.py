"""Neural posterior estimation of a twin's parameters, cached per device.

Method: amortised neural posterior estimation (NPE; Papamakarios & Murray, NeurIPS 2016;
Greenberg et al., ICML 2019) with the ``sbi`` package (Tejero-Cantero et al., JOSS 5,
2505 (2020)): a masked autoregressive flow learns p(parameters | summaries) from
simulations of the device drawn over the prior. Why NPE and not sequential Monte Carlo
ABC: NPE is trained once per device and then answers any file of that device in
seconds (the cache below; a second file, the 100-device calibration and the posterior
predictive checks are cheap), where SMC-ABC needs fresh simulations, thousands per
file, for every file and every calibration device.

The trained flow is cached under :func:`nirglucose.optics.lut.cache.cache_dir` /
``twin/<key>/`` (:meth:`TwinDevice.cache_key`: device, settings, package version) as
``posterior.safetensors`` (the flow's weights) and ``posterior.json`` (what it was
trained for, the summaries' prior-predictive range): loading executes no code from the
files. Training is seeded and single-threaded: the same settings give the same flow.
"""

from __future__ import annotations

import contextlib
import io
import json
import logging
import time
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..dataset import atomic_write
from ..exceptions import ConfigError, DataError
from ..optics.lut.cache import cache_dir
from .device import TwinDevice
from .parameters import Parameter
from .simulate import device_seeds, simulate_summaries
from .summaries import SUMMARY_VERSION, summary_names

__all__ = ["InferenceSettings", "PosteriorEstimator", "train_posterior", "load_or_train",
           "REACH_QUANTILES"]

_log = logging.getLogger(__name__)

#: Rounds of rejection sampling (each 2n flow draws) before outside draws are clipped.
_REJECTION_ROUNDS = 5
#: A file's summary outside this central range of the prior-predictive simulations is
#: out of the simulator's reach (named in a warning).
REACH_QUANTILES = (0.005, 0.995)


@dataclass(frozen=True)
class InferenceSettings:
    """How the posterior estimator is trained.

    Parameters
    ----------
    n_simulations : int
        Simulated devices drawn from the prior to train on. [-]
    seed : int
        Seed of the prior draws, the simulations and the training. [-]
    hidden_features, num_transforms : int
        Width and depth of the masked autoregressive flow (sbi's defaults). [-]
    max_epochs : int
        Upper limit of training epochs (training stops earlier when the validation loss
        has not improved for 20 epochs, sbi's default). [-]
    batch_size : int
        Simulations per training step (sbi's default 200; 400 halves the steps per epoch
        on two shared cores). [-]
    learning_rate : float
        Adam's step size (sbi's default 5e-4, doubled with the batch). [-]
    recalibration_devices : int
        Simulated devices, apart from the training's, on which each parameter's posterior
        is widened about its median until its central 90 % interval covers the truth 90 %
        of the time (never narrowed; 0: no widening). NPE is often overconfident at a
        small simulation budget (Hermans et al., TMLR 2022); the calibration benchmark
        checks the result on devices apart from both. [-]
    """

    n_simulations: int = 6000
    seed: int = 0
    hidden_features: int = 50
    num_transforms: int = 5
    max_epochs: int = 200
    batch_size: int = 400
    learning_rate: float = 1e-3
    recalibration_devices: int = 200

    def __post_init__(self) -> None:
        for name, least in (("n_simulations", 200), ("hidden_features", 4),
                            ("num_transforms", 1), ("max_epochs", 1), ("batch_size", 16),
                            ("recalibration_devices", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise ConfigError(f"{name} must be an integer >= {least}, got {value!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"seed must be a non-negative integer, got {self.seed!r}")
        if not (isinstance(self.learning_rate, float) and 0 < self.learning_rate < 1):
            raise ConfigError(f"learning_rate must be a number in (0, 1), got "
                              f"{self.learning_rate!r}")


@contextlib.contextmanager
def _one_thread(seed: int):
    """Seeded, single-threaded torch for the block (restored after)."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    torch.manual_seed(seed)
    try:
        yield torch
    finally:
        torch.set_num_threads(threads)


class _NoTracker:
    """sbi's ``Tracker`` protocol, recording nothing: its default writes TensorBoard logs
    into ``./sbi-logs`` of whatever directory the user runs in (the training summary the
    twin keeps is sbi's ``summary`` dict)."""

    log_dir = None

    def log_metric(self, name, value, step=None) -> None:
        """Nothing."""

    def log_metrics(self, metrics, step=None) -> None:
        """Nothing."""

    def log_params(self, params) -> None:
        """Nothing."""

    def add_figure(self, name, figure, step=None) -> None:
        """Nothing."""

    def flush(self) -> None:
        """Nothing."""


def _builder(settings: InferenceSettings):
    from sbi.neural_nets import posterior_nn

    return posterior_nn(model="maf", hidden_features=settings.hidden_features,
                        num_transforms=settings.num_transforms)


def _prior(bounds: np.ndarray):
    import torch
    from sbi.utils import BoxUniform

    return BoxUniform(low=torch.tensor(bounds[:, 0], dtype=torch.float32),
                      high=torch.tensor(bounds[:, 1], dtype=torch.float32))


class PosteriorEstimator:
    """A trained flow p(fitting-scale parameters | summaries) and what it was trained for.

    Parameters
    ----------
    net : torch.nn.Module
        sbi's conditional density estimator.
    meta : dict
        ``keys``, ``bounds`` (fitting scale), ``summaries`` (names), ``reach_low``,
        ``reach_high``, ``settings``, ``n_train``, ``train_s``.
    """

    def __init__(self, net, meta: dict[str, Any]):
        from sbi.inference.posteriors import DirectPosterior

        self.net = net
        self.meta = meta
        #: Share of the last :meth:`sample` call's flow draws outside the priors. [-]
        self.leakage = 0.0
        self.bounds = np.asarray(meta["bounds"], dtype=float)
        self._posterior = DirectPosterior(posterior_estimator=net, prior=_prior(self.bounds))

    def sample(self, x: np.ndarray, n: int, seed: int, *, widen: bool = True) -> np.ndarray:
        """``n`` posterior draws (fitting scale) given one summary vector ``x``, widened
        about each parameter's median by its factor (``meta["widening"]``) and kept
        inside the prior's bounds."""
        z = self._inside_prior(x, n, seed)
        factor = np.asarray(self.meta.get("widening") or np.ones(z.shape[1]))
        if not widen or np.all(factor == 1.0):
            return z
        med = np.median(z, axis=0)
        return np.clip(med + factor * (z - med), self.bounds[:, 0], self.bounds[:, 1])

    def _inside_prior(self, x: np.ndarray, n: int, seed: int) -> np.ndarray:
        """``n`` flow draws inside the prior's box: rejection, a bounded number of rounds
        (for a file far from every simulation the flow may put most of its mass outside,
        where sbi's own rejection loop would not end); whatever is still missing is the
        outside draws clipped to the box. ``self.leakage``: the share drawn outside."""
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        inside, clipped, drawn = [], [], 0
        with _one_thread(seed) as torch, warnings.catch_warnings():
            warnings.simplefilter("ignore")  # sbi's note on outside draws: self.leakage
            xt = torch.tensor(np.asarray(x, dtype=np.float32)[None, :])
            for _ in range(_REJECTION_ROUNDS):
                z = self._posterior.sample((2 * n,), x=xt, show_progress_bars=False,
                                           reject_outside_prior=False).detach().numpy()
                z = z.astype(float)
                ok = np.all((z >= lo) & (z <= hi), axis=1)
                drawn += len(z)
                inside.append(z[ok])
                clipped.append(np.clip(z[~ok], lo, hi))
                if sum(len(k) for k in inside) >= n:
                    break
        z_in = np.concatenate(inside)
        self.leakage = 1.0 - len(z_in) / drawn
        return np.concatenate([z_in, *clipped])[:n]

    def log_prob(self, z: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Posterior log density (unnormalised) of fitting-scale draws ``z`` given ``x``."""
        with _one_thread(0) as torch:
            xt = torch.tensor(np.asarray(x, dtype=np.float32)[None, :])
            zt = torch.tensor(np.asarray(z, dtype=np.float32))
            # unnormalised: the leakage correction (a constant per x) would cost 10^4
            # draws per call and does not move the most probable draw
            lp = self._posterior.log_prob(zt, x=xt, norm_posterior=False)
            return lp.detach().numpy().astype(float)

    def out_of_reach(self, x: np.ndarray) -> list[str]:
        """Names of the summaries of ``x`` outside the prior-predictive range."""
        lo, hi = np.asarray(self.meta["reach_low"]), np.asarray(self.meta["reach_high"])
        x = np.asarray(x, dtype=float)
        return [n for n, v, a, b in zip(self.meta["summaries"], x, lo, hi, strict=True)
                if not a <= v <= b]

    def save(self, folder: Path) -> None:
        """Write ``posterior.safetensors`` and ``posterior.json`` into ``folder``."""
        from safetensors.torch import save_file

        folder.mkdir(parents=True, exist_ok=True)
        state = {k: v.detach().contiguous() for k, v in self.net.state_dict().items()}
        atomic_write(folder / "posterior.safetensors", lambda p: save_file(state, p))
        atomic_write(folder / "posterior.json",
                     lambda p: Path(p).write_text(json.dumps(self.meta, indent=1)))

    @classmethod
    def load(cls, folder: Path, expected: dict[str, Any]) -> PosteriorEstimator | None:
        """The cached estimator in ``folder`` when it was trained for ``expected``
        (keys, bounds, summaries, settings, version); None when absent or stale."""
        from safetensors.torch import load_file

        try:
            meta = json.loads((folder / "posterior.json").read_text())
            state = load_file(str(folder / "posterior.safetensors"))
        except (OSError, ValueError):
            return None
        if any(meta.get(k) != v for k, v in expected.items()):
            _log.info("twin cache %s is for other settings; training anew", folder)
            return None
        settings = InferenceSettings(**meta["settings"])
        n_par, n_sum = len(meta["keys"]), len(meta["summaries"])
        with _one_thread(0) as torch:
            net = _builder(settings)(torch.zeros(2, n_par), torch.randn(2, n_sum))
            try:
                net.load_state_dict(state)
            except RuntimeError:
                return None
        net.eval()
        return cls(net, meta)


def _expected(params: list[Parameter], names: list[str], settings: InferenceSettings):
    return {"keys": [p.key for p in params],
            "bounds": [list(p.fit_bounds) for p in params], "summaries": names,
            "settings": asdict(settings), "version": __version__,
            "summary_version": SUMMARY_VERSION, "format": 2}


def train_posterior(device: TwinDevice, params: list[Parameter],
                    settings: InferenceSettings, n_jobs: int = 1) -> PosteriorEstimator:
    """Simulate ``settings.n_simulations`` devices over the prior and train the flow.

    Raises
    ------
    DataError
        Fewer than half the prior draws could be simulated.
    """
    from sbi.inference import NPE

    t0 = time.perf_counter()
    names = summary_names(device)
    bounds = np.array([p.fit_bounds for p in params])
    rng = np.random.default_rng(np.random.SeedSequence([settings.seed, 1]))
    z = rng.uniform(bounds[:, 0], bounds[:, 1], size=(settings.n_simulations, len(params)))
    values = np.column_stack([p.from_fit(z[:, i]) for i, p in enumerate(params)])
    x = simulate_summaries(device, [p.key for p in params], values,
                           device_seeds(settings.seed, settings.n_simulations), n_jobs)
    ok = np.isfinite(x).all(axis=1)
    if ok.sum() < settings.n_simulations / 2:
        raise DataError(f"only {int(ok.sum())} of {settings.n_simulations} prior draws could "
                        "be simulated for this device; its parameters' priors need narrowing")
    z, x = z[ok], x[ok]
    sim_s = time.perf_counter() - t0
    with _one_thread(settings.seed) as torch, warnings.catch_warnings(record=True) as notes:
        warnings.simplefilter("always")
        inference = NPE(prior=_prior(bounds), density_estimator=_builder(settings),
                        show_progress_bars=False, tracker=_NoTracker())
        inference.append_simulations(torch.tensor(z, dtype=torch.float32),
                                     torch.tensor(x, dtype=torch.float32))
        printed = io.StringIO()  # sbi prints its convergence line: library code never prints
        with contextlib.redirect_stdout(printed):
            net = inference.train(max_num_epochs=settings.max_epochs,
                                  training_batch_size=settings.batch_size,
                                  learning_rate=settings.learning_rate, show_train_summary=False)
        epochs = int(inference.summary["epochs_trained"][-1])
        val = float(inference.summary["best_validation_loss"][-1])
    net.eval()
    lo, hi = np.quantile(x, REACH_QUANTILES, axis=0)
    meta = {**_expected(params, names, settings), "reach_low": lo.tolist(),
            "reach_high": hi.tolist(), "n_train": int(ok.sum()), "epochs": epochs,
            "best_validation_loss": val, "simulate_s": round(sim_s, 1),
            "train_s": round(time.perf_counter() - t0 - sim_s, 1),
            "training_notes": sorted({str(w.message) for w in notes})}
    for note in [*meta["training_notes"], printed.getvalue().strip()]:  # sbi's diagnostics
        if note:
            _log.info("twin training: %s", note)
    est = PosteriorEstimator(net, meta)
    t1 = time.perf_counter()
    est.meta["widening"] = _widening(est, device, params, settings, n_jobs)
    est.meta["recalibrate_s"] = round(time.perf_counter() - t1, 1)
    return est


#: Seed offset of the recalibration devices (apart from the training's, seed offset 0,
#: and the calibration benchmark's, nirglucose.twin.calibration).
_RECAL_SEED_OFFSET = 2_000_003
#: Draws per recalibration device, and the widening factors tried. [-]
_RECAL_DRAWS = 300
_WIDENING_GRID = np.round(np.arange(1.0, 4.0001, 0.05), 2)


def _widening(est: PosteriorEstimator, device: TwinDevice, params: list[Parameter],
              settings: InferenceSettings, n_jobs: int) -> list[float]:
    """Per parameter, the smallest factor (>= 1) that widens its central 90 % posterior
    interval about the median until it covers the truth on 90 % of
    ``settings.recalibration_devices`` devices drawn from the prior."""
    n = settings.recalibration_devices
    if n == 0:
        return [1.0] * len(params)
    bounds = est.bounds
    rng = np.random.default_rng(np.random.SeedSequence([settings.seed, 6]))
    z_true = rng.uniform(bounds[:, 0], bounds[:, 1], size=(n, len(params)))
    values = np.column_stack([p.from_fit(z_true[:, i]) for i, p in enumerate(params)])
    x = simulate_summaries(device, [p.key for p in params], values,
                           device_seeds(settings.seed + _RECAL_SEED_OFFSET, n), n_jobs)
    rows = np.flatnonzero(np.isfinite(x).all(axis=1))
    q = np.array([np.quantile(est.sample(x[j], _RECAL_DRAWS, settings.seed + int(j),
                                         widen=False), [0.05, 0.5, 0.95], axis=0)
                  for j in rows])  # (devices, 3, params)
    truth = z_true[rows]
    out = []
    for i in range(len(params)):
        lo, med, hi = q[:, 0, i], q[:, 1, i], q[:, 2, i]
        for k in _WIDENING_GRID:
            a = np.maximum(med + k * (lo - med), bounds[i, 0])
            b = np.minimum(med + k * (hi - med), bounds[i, 1])
            if np.mean((a <= truth[:, i]) & (truth[:, i] <= b)) >= 0.9:
                break
        out.append(float(k))
    return out


def load_or_train(device: TwinDevice, params: list[Parameter], settings: InferenceSettings,
                  *, cache: bool = True, n_jobs: int = 1) -> tuple[PosteriorEstimator, bool]:
    """The device's estimator from the cache, else trained (and cached when ``cache``).

    Returns
    -------
    (PosteriorEstimator, bool)
        The estimator, and whether it came from the cache.
    """
    folder = cache_dir() / "twin" / device.cache_key(
        {**asdict(settings), "summary_version": SUMMARY_VERSION})
    expected = _expected(params, summary_names(device), settings)
    if cache:
        found = PosteriorEstimator.load(folder, expected)
        if found is not None:
            return found, True
    est = train_posterior(device, params, settings, n_jobs=n_jobs)
    if cache:
        try:
            est.save(folder)
        except (OSError, DataError) as exc:  # a read-only cache costs time, not the result
            _log.warning("could not cache the twin's estimator in %s: %s", folder, exc)
    return est, False
