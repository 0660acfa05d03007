"""
Deep approximators trained online, one sample at a time: the networks of :class:`~sb3_aac.sarsa_aac.policies.DeepPolicy`.

Three feed-forward networks read the normalised observation: the action-type actor (K outputs ``Q_k``), the parameter
actor (P outputs, the scaled parameters in ``[-1, 1]``) and the critic (``V``). Following Elsayed, Vasan & Mahmood
2024, "Streaming Deep Reinforcement Learning Finally Works" (arXiv 2410.14606), each hidden layer is
``linear -> layer norm (no affine map) -> leaky ReLU``, the linear layers start sparse (in each unit a random 90 % of
the input weights are 0, the rest uniform in ``+-1 / sqrt(fan_in)``, biases 0), the observations are normalised by
their running mean and variance, and every step is an overshooting-bounded gradient step (ObGD) on an eligibility
trace:

- per sample ``i`` of network ``f`` with error ``delta_i`` (in the network's units, see below) and trace
  ``z_i <- gamma * lambda * z_i + grad f(s_i)`` (``z_i = grad f(s_i)`` without traces), the step is
  ``alpha_i * delta_i * z_i`` with ``alpha_i = alpha / max(1, alpha * kappa * max(|delta_i|, 1) * ||z_i||_1)``:
  Elsayed et al.'s Algorithm 3, which shrinks the step whenever it could move the output past its target.

SarsaAAC's rule gives the errors (see :class:`sb3_aac.SarsaAAC`): the critic's TD error, the chosen type's SARSA
error (``grad f`` is that of ``Q_k``), and for the parameter actor the CACLA error vector ``e_i`` (the executed minus
the predicted parameters of the chosen type, where ``delta > 0``), for which the step is ObGD's with
``delta_i = max_j |e_ij|`` and ``z_i = J_i^T e_i / delta_i`` (``J_i`` the Jacobian of the parameter outputs; with one
parameter this is ObGD exactly). The parameter actor learns one step at a time (no trace): its target is the executed
parameters, not a return.

Units: the action-type actor and the critic compute their outputs in reward units, but learn in units of
SarsaAAC's ``return_scale`` ``u`` (passed as ``hidden_gain = u**-2``): their errors are divided by ``u`` and their
output layers are read as ``weight / u``, so ObGD's bound and every step are the same whatever the reward units.

Lanes (a VecEnv of ``n`` lanes): each lane has its own trace, and each lane's sample takes the ObGD step it would take
alone at the current weights, so the per-sample step does not depend on ``n``; with one lane this is stream ObGD
exactly. The lanes' steps are added (as ``n`` steps taken one after another would be, to first order in the step);
where that sum would carry the batch past the minimum of its squared errors along the summed step's direction (to first
order: ``t* = sum_i delta_i c_i / sum_i c_i**2 < 1``, ``c_i`` the change of sample ``i``'s output), it is shortened to
``t*`` (one factor per network and step). So steps of similar samples cannot overshoot together, while samples that
pull apart keep their own steps. At most :data:`~sb3_aac.sarsa_aac.lane_steps.LANE_CHUNK` lanes are summed so: more
lanes are updated in chunks of that many, one chunk after another, each chunk's errors measured on the weights the
earlier chunks left (one summed step for 256 similar lanes would shrink to about one sample's step). What does not
hold: within a chunk the TD errors are all measured before any of its steps, so the curve per env step is the same only
to first order; measured on the navigation env (seed 0), 1 and 16 lanes both solve it after 30k env steps (0.995 and
0.970 success), but 16 lanes lag early (0.305 against 0.675 after 8k).

The parameters are float64 torch tensors (for SB3's save/load); the forward pass is
:class:`sb3_aac.runtime.forward.NetworkForward` (the exported runtime's code) and :class:`DeepKernel` adds the
backward pass and the steps in numpy, on zero-copy views of the parameters.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from typing import Any, NamedTuple

import numpy as np
import torch as th
from torch import nn

from sb3_aac.sarsa_aac.approximators import NumpyBank
from sb3_aac.runtime.forward import NetworkForward

# Layer norm's epsilon (torch's default), leaky ReLU's slope (torch's default) and the share of zero input weights
# of each unit at initialisation (Elsayed et al. 2024).
LAYER_NORM_EPS = 1e-5
LEAKY_SLOPE = 0.01
DEFAULT_SPARSITY = 0.9
# Added to the observations' running variance before its square root (Elsayed et al. 2024 use 1e-8).
OBS_VARIANCE_EPS = 1e-8
MAX_HIDDEN_UNITS = 4096


def sparse_uniform(fan_out: int, fan_in: int, sparsity: float, rng: np.random.Generator) -> np.ndarray:
    """
    A ``(fan_out, fan_in)`` weight matrix: uniform in ``+-1 / sqrt(fan_in)`` with ``ceil(sparsity * fan_in)`` zeros at
    random positions in each row (at most ``fan_in - 1``, so that every unit reads some input).
    """
    bound = 1.0 / math.sqrt(fan_in)
    weight = rng.uniform(-bound, bound, (fan_out, fan_in))
    n_zeros = min(math.ceil(sparsity * fan_in), fan_in - 1)
    if n_zeros > 0:
        zeros = np.argsort(rng.random((fan_out, fan_in)), axis=1)[:, :n_zeros]
        np.put_along_axis(weight, zeros, 0.0, axis=1)
    return weight


def check_net_arch(net_arch: Any) -> tuple[int, ...]:
    """``net_arch`` as a tuple of hidden sizes, or a ``ValueError`` naming the allowed range."""
    if not isinstance(net_arch, (list, tuple)) or not all(type(h) is int and 1 <= h <= MAX_HIDDEN_UNITS for h in net_arch):
        raise ValueError(
            f"net_arch must be a list of hidden layer sizes, each a whole number in [1, {MAX_HIDDEN_UNITS}] "
            f"([] for linear networks), got {net_arch!r}"
        )
    return tuple(net_arch)


class DeepCache(NamedTuple):
    """What :meth:`DeepKernel.forward` computed and :meth:`DeepKernel.update` needs: per network, the layers' cache
    of :meth:`~sb3_aac.runtime.forward.NetworkForward.network` (``N`` rows each)."""

    layers: list[list[tuple[np.ndarray, ...]]]


class DeepTraces:
    """
    The eligibility traces of the action-type actor's and the critic's networks, one per lane: per traced network
    ``i`` and linear layer, a weight trace ``(n, out, in)`` (``weights[i]``) and a bias trace ``(n, out)``
    (``biases[i]``); they decay by ``decay = gamma * lambda`` per step.
    """

    def __init__(self, weights: dict[int, list[np.ndarray]], biases: dict[int, list[np.ndarray]], decay: float):
        self.weights, self.biases, self.decay = weights, biases, decay

    @classmethod
    def zeros(cls, n_lanes: int, shapes: dict[int, list[tuple[int, int]]], decay: float) -> DeepTraces:
        """Zero traces of ``n_lanes`` lanes; ``shapes``: per traced network, its linear layers' ``(out, in)``."""
        weights = {i: [np.zeros((n_lanes, *shape)) for shape in layer_shapes] for i, layer_shapes in shapes.items()}
        biases = {i: [np.zeros((n_lanes, shape[0])) for shape in layer_shapes] for i, layer_shapes in shapes.items()}
        return cls(weights, biases, decay)

    def lanes(self, lanes: slice) -> DeepTraces:
        """The traces of a range of lanes, as views (a step on them updates these)."""
        weights = {i: [trace[lanes] for trace in traces] for i, traces in self.weights.items()}
        biases = {i: [trace[lanes] for trace in traces] for i, traces in self.biases.items()}
        return DeepTraces(weights, biases, self.decay)

    def clear(self, lanes: np.ndarray) -> None:
        """Zero the traces of ``lanes`` (their episodes ended)."""
        for traces in (*self.weights.values(), *self.biases.values()):
            for trace in traces:
                trace[lanes] = 0.0


class DeepBank(NumpyBank):
    """
    The deep policy's networks over one observation vector (see the module docstring); outputs in SarsaAAC's column
    layout: ``Q_0..Q_{K-1}``, the ``n_params`` scaled parameters, ``V``.

    :param low: ``(D,)`` lower bounds of the observation (scaling before the first observation arrives, and always
        without ``normalize_obs``; an infinite bound leaves its input unscaled)
    :param high: ``(D,)`` upper bounds
    :param n_types: K
    :param n_params: P
    :param net_arch: hidden layer sizes of each network
    :param sparsity: share of zero input weights per unit at initialisation, in ``[0, 1)``
    :param normalize_obs: normalise each input by the running mean and standard deviation of the observations seen
        in training (:meth:`observe`)
    :param kappa: ObGD's overshooting factor ``kappa > 0``
    :param seed: seed of the initialisation (None: from torch's global generator)
    """

    def __init__(
        self,
        low: np.ndarray,
        high: np.ndarray,
        n_types: int,
        n_params: int,
        net_arch: tuple[int, ...],
        sparsity: float,
        normalize_obs: bool,
        kappa: float,
        seed: int | None = None,
    ):
        super().__init__()
        if not (isinstance(sparsity, (int, float)) and 0 <= sparsity < 1):  # type: ignore[redundant-expr]
            raise ValueError(f"sparsity must be in [0, 1) (the share of zero weights at initialisation), got {sparsity!r}")
        if not (isinstance(kappa, (int, float)) and 0 < kappa < math.inf):  # type: ignore[redundant-expr]
            raise ValueError(f"kappa must be a finite number > 0 (ObGD's overshooting factor; 2 in the paper), got {kappa!r}")
        net_arch = check_net_arch(net_arch)
        low, high = np.asarray(low, dtype=np.float64).ravel(), np.asarray(high, dtype=np.float64).ravel()
        finite = np.isfinite(low) & np.isfinite(high)
        low, high = np.where(finite, low, -1.0), np.where(finite, high, 1.0)
        self.n_inputs, self.n_outputs = len(low), n_types + n_params + 1
        self.net_arch, self.sparsity, self.normalize_obs, self.kappa = net_arch, float(sparsity), normalize_obs, float(kappa)
        self.register_buffer("obs_mid", th.as_tensor((high + low) / 2))
        self.register_buffer("obs_half", th.as_tensor((high - low) / 2))
        # Running observation statistics: count, mean, sum of squared deviations (Chan et al.'s parallel update).
        self.register_buffer("obs_count", th.zeros(1, dtype=th.float64))
        self.register_buffer("obs_mean", th.zeros(self.n_inputs, dtype=th.float64))
        self.register_buffer("obs_m2", th.zeros(self.n_inputs, dtype=th.float64))
        columns = {"q": (0, n_types), "params": (n_types, n_types + n_params), "value": (n_types + n_params, self.n_outputs)}
        rng = np.random.default_rng(seed if seed is not None else int(th.randint(0, 2**31 - 1, ()).item()))
        self.networks: list[dict[str, Any]] = []
        # What each network computes: "q" (action-type actor), "params" (parameter actor, absent if P == 0), "value".
        self.roles = [role for role, (start, stop) in columns.items() if stop > start]
        for start, stop in (columns[role] for role in self.roles):
            i, size = len(self.networks), self.n_inputs
            layers: list[dict[str, Any]] = []
            for width in (*net_arch, stop - start):
                j = len(layers)
                layers.append({"type": "linear", "in": size, "out": width})
                self._parameter(f"net{i}_{j}_weight", sparse_uniform(width, size, self.sparsity, rng))
                self._parameter(f"net{i}_{j}_bias", np.zeros(width))
                if len(layers) < 3 * len(net_arch):  # a hidden layer
                    layers.append({"type": "layernorm", "size": width, "eps": LAYER_NORM_EPS, "affine": False})
                    layers.append({"type": "activation", "function": "leaky_relu", "slope": LEAKY_SLOPE})
                size = width
            self.networks.append({"columns": [start, stop], "layers": layers})
        self.output_layers = [len(network["layers"]) - 1 for network in self.networks]

    def _parameter(self, name: str, values: np.ndarray) -> None:
        self.register_parameter(name, nn.Parameter(th.as_tensor(values, dtype=th.float64), requires_grad=False))

    def _make_kernel(self) -> DeepKernel:
        return DeepKernel(self)

    def _forward_pass(self) -> NetworkForward:
        arrays = self.arrays()
        return NetworkForward(arrays["obs_mid"], arrays["obs_half"], self.networks, arrays, self.n_outputs)

    def network_of(self, column: int) -> int:
        """The network that computes output ``column``."""
        return next(i for i, net in enumerate(self.networks) if net["columns"][0] <= column < net["columns"][1])

    def scale_outputs(self, outputs: list[int], factor: float) -> None:
        """Multiply the given outputs by ``factor`` (the rows of their networks' output layers)."""
        with th.no_grad():
            for column in outputs:
                i = self.network_of(column)
                row = column - self.networks[i]["columns"][0]
                getattr(self, f"net{i}_{self.output_layers[i]}_weight")[row] *= factor
                getattr(self, f"net{i}_{self.output_layers[i]}_bias")[row] *= factor

    def finite_outputs(self) -> np.ndarray:
        """``(A,)`` bool: whether every parameter of the network computing each output is finite."""
        finite = np.ones(self.n_outputs, dtype=bool)
        for name, p in self.named_parameters():
            i = int(name[3 : name.index("_")])
            start, stop = self.networks[i]["columns"]
            finite[start:stop] &= bool(th.isfinite(p).all())
        return finite

    def observe(self, obs: np.ndarray) -> None:
        """
        Fold a batch of observations ``(n, D)`` into the running mean and variance and, with ``normalize_obs``, use
        them from now on: input ``i`` is scaled as ``(s_i - mean_i) / sqrt(var_i + 1e-8)`` (once two observations
        were seen). CPU storage only (training).
        """
        if self.normalize_obs:
            kernel = self.numpy_kernel()
            assert isinstance(kernel, DeepKernel)
            kernel.observe(obs)

    def new_traces(self, n_lanes: int, decay: float) -> DeepTraces:
        """Zero traces of the action-type actor's and the critic's networks (not the parameter actor's), per lane."""
        shapes = {
            i: [(layer["out"], layer["in"]) for layer in self.networks[i]["layers"] if layer["type"] == "linear"]
            for i, role in enumerate(self.roles)
            if role != "params"
        }
        return DeepTraces.zeros(n_lanes, shapes, decay)


class DeepKernel(NetworkForward):
    """
    The numpy forward pass (:class:`~sb3_aac.runtime.forward.NetworkForward`) of a :class:`DeepBank`, with its cache
    and the ObGD steps of training (see the module docstring), on views of the bank's CPU parameters.
    """

    def __init__(self, bank: DeepBank):
        if bank.obs_mid.device.type != "cpu":
            raise ValueError(f"The numpy kernel needs CPU tensors, the bank is on {bank.obs_mid.device}")
        arrays = bank.arrays()
        super().__init__(arrays["obs_mid"], arrays["obs_half"], bank.networks, arrays, bank.n_outputs)
        self.roles, self.kappa = bank.roles, bank.kappa
        # Views of the observation statistics and of the input scaling they set.
        self._obs_count, self._obs_mean, self._obs_m2 = arrays["obs_count"], arrays["obs_mean"], arrays["obs_m2"]
        self._obs_mid, self._obs_half = arrays["obs_mid"], arrays["obs_half"]

    def observe(self, obs: np.ndarray) -> None:
        """:meth:`DeepBank.observe` (Chan et al.'s parallel update of the count, mean and squared deviations)."""
        count, n = self._obs_count[0], len(obs)
        batch_mean = obs.sum(0) / n
        deviation = batch_mean - self._obs_mean
        total = count + n
        centred = obs - batch_mean
        self._obs_m2 += (centred * centred).sum(0) + deviation * deviation * (count * n / total)
        self._obs_mean += deviation * (n / total)
        self._obs_count[0] = total
        if total >= 2:
            self._obs_mid[:] = self._obs_mean
            np.sqrt(self._obs_m2 / total + OBS_VARIANCE_EPS, out=self._obs_half)
            self.set_input_scaling(self._obs_mid, self._obs_half)

    def forward(self, obs: np.ndarray, roles: Collection[str] | None = None) -> tuple[np.ndarray, DeepCache]:
        """
        ``obs``: ``(n, D)`` -> outputs ``(n, A)`` and the cache for :meth:`update`. With ``roles`` (of ``"q"``,
        ``"params"``, ``"value"``), only those networks run: the others' outputs are 0 and :meth:`update` leaves them
        (and their traces) as they are.
        """
        x = self.features(obs)
        out = np.empty((len(x), self.n_outputs)) if roles is None else np.zeros((len(x), self.n_outputs))
        layers: list[list[tuple[np.ndarray, ...]]] = []
        for i, (start, stop) in enumerate(self.columns):
            layers.append([])
            if roles is None or self.roles[i] in roles:
                out[:, start:stop] = self.network(i, x, layers[-1])
        return out, DeepCache(layers)

    def update(
        self,
        cache: DeepCache,
        err: np.ndarray,
        lr: np.ndarray,
        hidden_gain: np.ndarray | None = None,
        types: np.ndarray | None = None,
        traces: DeepTraces | None = None,
    ) -> None:
        """
        One ObGD step of every network for a batch of samples (see the module docstring), in place.

        :param cache: from :meth:`forward` on the same weights; its first ``n`` rows are used; the networks it did not
            run are not updated
        :param err: ``(n, A)`` target minus output (SarsaAAC's layout: the chosen type's SARSA error in its Q column,
            CACLA errors of the chosen type's parameters, the TD error in the V column; 0 elsewhere)
        :param lr: ``(A,)`` ObGD's ``alpha`` of each output's network (read at the network's first column)
        :param hidden_gain: ``(A,)`` ``1 / u**2`` for outputs in units of ``u`` (None: 1)
        :param types: ``(n,)`` the chosen types (whose Q gradient enters the trace); None: the Q column with the
            largest error
        :param traces: the lanes' traces (:meth:`DeepBank.new_traces`), or None for one-step updates
        """
        n = len(err)
        for i, (start, stop) in enumerate(self.columns):
            if not cache.layers[i]:  # not run by forward
                continue
            role = self.roles[i]
            unit = 1.0 if hidden_gain is None else float(hidden_gain[start]) ** -0.5
            e = err[:, start:stop] / unit
            if role == "q":
                k = np.abs(e).argmax(1) if types is None else types
                rows = np.arange(n)
                delta = e[rows, k]
                direction = np.zeros_like(e)
                direction[rows, k] = 1.0
            elif role == "params":
                delta = np.abs(e).max(1)
                direction = np.divide(e, delta[:, None], out=np.zeros_like(e), where=delta[:, None] > 0)
            else:
                delta, direction = e[:, 0], np.ones_like(e)
            grads = self._backward(i, cache.layers[i], direction, unit, n)
            steps = self._obgd_steps(i, grads, delta, float(lr[start]), None if traces is None or role == "params" else traces)
            self._apply(i, steps, unit)

    def _backward(
        self, i: int, cache: list[tuple[np.ndarray, ...]], direction: np.ndarray, unit: float, n: int
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """
        Per-sample gradients of ``direction . f / unit`` for network ``i``, factorised: per linear layer (input first),
        the pair (gradient at its output ``(n, out)``, its input ``(n, in)``); the weight gradient of sample ``s`` is
        their outer product, the bias gradient the first.
        """
        g = direction
        grads = []
        layers = self.layers[i]
        last = len(layers) - 1
        for j in range(last, -1, -1):
            kind, weight, _, constant = layers[j]
            h_in = cache[j][0][:n]
            if kind == "linear":
                grads.append((g, h_in))
                if j > 0:
                    g = g @ (weight / unit if j == last else weight)  # type: ignore[operator]
            elif kind == "layernorm":
                y, inv_std = cache[j][1][:n], cache[j][2][:n]
                size = g.shape[-1]
                g = inv_std * (g - g.sum(-1, keepdims=True) / size - y * ((g * y).sum(-1, keepdims=True) / size))
            elif kind == "tanh":
                t = np.tanh(h_in)
                g = g * (1.0 - t * t)
            elif kind == "relu":
                g = g * (h_in > 0.0)
            else:
                g = g * np.where(h_in > 0.0, 1.0, constant)
        grads.reverse()
        return grads

    def _obgd_steps(
        self, i: int, grads: list[tuple[np.ndarray, np.ndarray]], delta: np.ndarray, alpha: float, traces: DeepTraces | None
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """The summed, bounded ObGD steps (weight, bias) of network ``i``'s linear layers, in the network's units."""
        if traces is not None:
            z_w, z_b = traces.weights[i], traces.biases[i]
            for (a, x), tw, tb in zip(grads, z_w, z_b, strict=True):
                tw *= traces.decay
                tw += a[:, :, None] * x[:, None, :]
                tb *= traces.decay
                tb += a
            norm1 = sum(np.abs(tw).sum((1, 2)) + np.abs(tb).sum(1) for tw, tb in zip(z_w, z_b, strict=True))
        else:
            norm1 = sum(np.abs(a).sum(1) * (np.abs(x).sum(1) + 1.0) for a, x in grads)
        scale = alpha / np.maximum(alpha * self.kappa * np.maximum(np.abs(delta), 1.0) * norm1, 1.0)
        w = scale * delta  # (n,)
        steps: list[tuple[np.ndarray, np.ndarray]] = []
        batch = len(w) > 1  # one sample's summed step is its own: no bound to apply
        moved = np.zeros_like(w)  # each sample's output change under the summed step (first order)
        for layer, (a, x) in enumerate(grads):
            if traces is not None:
                tw, tb = traces.weights[i][layer], traces.biases[i][layer]
                step_w, step_b = np.einsum("n,noi->oi", w, tw), w @ tb
            else:
                wa = w[:, None] * a
                step_w, step_b = wa.T @ x, wa.sum(0)
            if batch:
                moved += ((a @ step_w) * x).sum(1) + a @ step_b
            steps.append((step_w, step_b))
        # Past the minimum of the batch's squared errors along the step (to first order)? Shorten it to there.
        toward, length = delta @ moved, moved @ moved
        if batch and 0 < toward < length:
            steps = [(sw * (toward / length), sb * (toward / length)) for sw, sb in steps]
        return steps

    def _apply(self, i: int, steps: list[tuple[np.ndarray, np.ndarray]], unit: float) -> None:
        """Add the steps to network ``i``'s linear layers (the output layer's in stored units: ``unit`` times)."""
        linear = [(weight, bias) for kind, weight, bias, _ in self.layers[i] if kind == "linear"]
        for j, ((weight, bias), (step_w, step_b)) in enumerate(zip(linear, steps, strict=True)):
            factor = unit if j == len(linear) - 1 else 1.0
            weight += factor * step_w  # type: ignore[operator]
            bias += factor * step_b  # type: ignore[operator]
