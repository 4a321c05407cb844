"""Shallow dense neural network (SDNN) after Srichan et al. (2022): no physics.

Examples
--------
>>> import nirglucose as ng
>>> from nirglucose.models import SDNN
>>> ds = ng.simulate("wearable", n_subjects=10, per_subject=2, seed=0)
>>> SDNN(max_epochs=2, random_state=0).fit(ds).n_parameters
3713

References
----------
.. [1] C. Srichan, W. Srichan, P. Danvirutai, C. Ritsongmuang, A. Sharma and
   S. Anutrakulchai, "Non-invasively accuracy enhanced blood glucose sensor using
   shallow dense neural networks with NIR monitoring and medical features",
   Sci. Rep. 12, 1769 (2022). :doi:`10.1038/s41598-022-05570-8`
"""

from __future__ import annotations

from typing import ClassVar

from ._torch_base import TorchRegressor
from .networks import SDNNNet
from .registry import register

__all__ = ["SDNN"]


@register("sdnn")
class SDNN(TorchRegressor):
    """Shallow front end on the absorbances, then a deeper dense stack; MSE loss only.

    Network: :class:`~nirglucose.models.networks.SDNNNet` — 4 -> 16 on the four
    absorbances, concatenated with the 12 physiological values, then
    28 -> 48 -> 32 -> 16 -> 8 -> 1 (ReLU); 3,713 parameters, the study's count [1]_.

    Parameters
    ----------
    max_epochs, batch_size, lr, weight_decay, dropout, whiten_inputs, patience,
    val_fraction, lr_schedule, refit, random_state
        Training, see :class:`~nirglucose.models._torch_base.TorchRegressor`.

    Notes
    -----
    Srichan et al. trained a small dense network on multi-band NIR readings and
    personal medical features; the layer sizes here are a reconstruction chosen to
    match the reference study's 3,713 parameters, not theirs. The loss is the base
    class's MSE (no ``get_loss`` override).
    """

    privileged: ClassVar[str | None] = None

    def build_module(self) -> SDNNNet:
        """:class:`~nirglucose.models.networks.SDNNNet`."""
        return SDNNNet(**self._input_widths(), dropout=float(self.dropout))
