"""
SarsaAAC's policies: the abstract :class:`SarsaAACPolicy` (spaces, output layout, greedy ``predict``), the policies
on a numpy bank of approximators (:class:`NumpyBankPolicy`): the dense banks of the paper (:class:`DenseBankPolicy`
and its presets :class:`MlpPolicy`, :class:`RbfMlpPolicy`, :class:`RbfPolicy`), tile coding (:class:`TilePolicy`) and
deep networks trained online (:class:`DeepPolicy`).
"""

from __future__ import annotations

from abc import abstractmethod
from typing import Any, ClassVar

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.type_aliases import PyTorchObs

from sb3_aac.common.observations import check_box_observation_space, observation_batch
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.sarsa_aac.approximators import DEFAULT_RBF_WINDOW, ApproximatorBank, NumpyBank
from sb3_aac.sarsa_aac.deep import DEFAULT_SPARSITY, DeepBank, check_net_arch
from sb3_aac.sarsa_aac.kernels import Kernel
from sb3_aac.sarsa_aac.tile_coding import TileBank


class SarsaAACPolicy(BasePolicy):
    """
    Policy of SARSA Actor-Actor-Critic: the action-type actor, the parameter actor and the critic, as
    ``A = K + n_params + 1`` outputs of one observation (Uc-Cetina 2013, Fig. 3), column by column:
    ``Q_0..Q_{K-1}`` (action-type actor, :attr:`q_slice`), then one output per scalar parameter in the order of
    :class:`~sb3_aac.common.spaces.ParameterizedActionSpec` (parameter actor, in the scaled ``[-1, 1]`` space,
    :attr:`param_slice`), then ``V`` (critic, :attr:`value_index`).

    ``predict`` is greedy: the type with the greatest Q, and that type's parameter outputs clipped to the bounds.
    Exploration belongs to the algorithm (see :meth:`SarsaAAC.predict <sb3_aac.SarsaAAC.predict>`).

    This class builds no approximators. A family of approximators is one subclass that builds them in its
    ``__init__`` (after calling this one's, which sets the spaces and the layout; :meth:`input_bounds` gives the
    bounds to scale the inputs with) and implements the abstract methods below, which are the whole contract
    SarsaAAC and ``predict`` rely on, and ``_get_constructor_parameters`` (its own arguments, for save/load).

    :param observation_space: A ``Box`` observation space (any shape; it is flattened)
    :param action_space: A parameterized action space (see :mod:`sb3_aac.common.spaces`)
    :param obs_bounds: ``(low, high)`` of the (flattened) observation for the family's input scaling; defaults to the
        observation space's bounds
    """

    # SarsaAAC's learning rates when none is given: the step each family was tuned with (see SarsaAAC's docstring).
    default_learning_rate: ClassVar[float] = 0.1
    # SarsaAAC's replay_ratio when none is given: replayed transitions per live one where replay wins per second as
    # well as per sample on the paper env (docs/sarsa_aac_results.md, "Replay of recent transitions"), else 0.
    default_replay_ratio: ClassVar[int] = 0

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        obs_bounds: tuple[np.ndarray, np.ndarray] | None = None,
    ):
        check_box_observation_space(observation_space, "SarsaAAC policies")
        super().__init__(observation_space, action_space)
        self.spec = ParameterizedActionSpec.from_space(action_space)
        self.n_types, self.n_params = self.spec.n_types, self.spec.n_params
        self.n_outputs = self.n_types + self.n_params + 1
        self.obs_bounds = obs_bounds
        # Column layout of the outputs.
        self.q_slice = slice(0, self.n_types)
        self.param_slice = slice(self.n_types, self.n_types + self.n_params)
        self.value_index = self.n_types + self.n_params
        # param_table[u, k, j] = 1 if u == 1 and scalar parameter j belongs to type k (u: "update or not").
        owns = (self.spec.param_type == np.arange(self.n_types)[:, None]).astype(np.float64)
        self.param_table = np.stack([np.zeros_like(owns), owns])

    def input_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)``, each ``(D,)`` float64: ``obs_bounds`` if given, else the observation space's bounds."""
        box = self.observation_space
        assert isinstance(box, spaces.Box)  # checked in __init__
        low, high = (box.low, box.high) if self.obs_bounds is None else self.obs_bounds
        n_inputs = int(np.prod(box.shape))
        return (
            np.broadcast_to(np.asarray(low, dtype=np.float64).ravel(), (n_inputs,)),
            np.broadcast_to(np.asarray(high, dtype=np.float64).ravel(), (n_inputs,)),
        )

    # ------------------------------------------------------------------ the contract of a family

    @abstractmethod
    def evaluate(self, obs: np.ndarray) -> tuple[np.ndarray, Any]:
        """
        The outputs ``(n, A)`` (float64, column layout in the class docstring) of a float64 batch
        ``(n, *obs_shape)`` on the current weights, computed with numpy, wherever the weights are stored; and what
        the training kernel's update would need (the same as ``kernel().forward``'s cache on CPU storage).
        """

    @abstractmethod
    def kernel(self) -> Kernel[Any]:
        """The training kernel (:class:`~sb3_aac.sarsa_aac.kernels.Kernel`) on the current weights; CPU storage."""

    @abstractmethod
    def rebind(self) -> Kernel[Any]:
        """
        :meth:`kernel` built afresh: SarsaAAC calls it when ``learn`` starts, after the weights may have been moved,
        loaded or assigned (``param.data = ...``), and trains with the kernel it returns.
        """

    @abstractmethod
    def scale_outputs(self, columns: list[int], factor: float) -> None:
        """Multiply the outputs of ``columns`` by ``factor`` for every observation (in place, on the weights)."""

    @abstractmethod
    def finite_outputs(self) -> np.ndarray:
        """``(A,)`` bool: for each output, whether every weight it depends on is finite."""

    @property
    def chunks_lanes(self) -> bool:
        """Whether SarsaAAC updates this policy's lanes in chunks of at most
        :data:`~sb3_aac.sarsa_aac.lane_steps.LANE_CHUNK`, each chunk's errors measured on the weights the earlier
        chunks left: where every weight moves with every sample (hidden layers). False here (linear heads over fixed
        features take all lanes at once)."""
        return False

    # ------------------------------------------------------------------ built on the contract

    def scale_value_outputs(self, factor: float) -> None:
        """Multiply the outputs of the action-type actor and the critic (not the parameter actor's) by ``factor``."""
        self.scale_outputs([*range(self.n_types), self.value_index], factor)

    def forward(self, obs: PyTorchObs) -> th.Tensor:
        """All outputs ``(n, A)`` as a float64 tensor on ``obs``'s device (column layout in the class docstring)."""
        assert isinstance(obs, th.Tensor)
        return th.as_tensor(self.evaluate(obs.detach().cpu().numpy())[0], device=obs.device)

    def _predict(self, observation: PyTorchObs, deterministic: bool = True) -> th.Tensor:
        raise NotImplementedError("A parameterized action is not one tensor: use predict()")

    def actions_from_outputs(
        self, out: np.ndarray, k: np.ndarray | None = None, params: np.ndarray | None = None, vectorized: bool = True
    ) -> Any:
        """Env action(s) from outputs ``(n, A)``: greedy unless ``k`` / scaled ``params`` are given."""
        if k is None:
            k = out[:, self.q_slice].argmax(1)
        if params is None:
            params = out[:, self.param_slice]
        return self.spec.to_env_predicted(k, params, vectorized)

    def predict(  # type: ignore[override]
        self,
        observation: np.ndarray,
        state: tuple[np.ndarray, ...] | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = False,
    ) -> tuple[Any, tuple[np.ndarray, ...] | None]:
        """
        Greedy action(s) for one observation or a batch (``deterministic`` is accepted for SB3 compatibility;
        this policy has no stochastic mode of its own).

        :return: one env action (a tuple ``env.step`` accepts) for a single observation, or an object ndarray of
            shape ``(n,)`` holding one per observation for a batch; and ``state`` unchanged
        :raises ValueError: for an observation of the wrong shape, or with NaN or inf values
        """
        obs, vectorized = observation_batch(observation, self.observation_space)
        out, _ = self.evaluate(obs)
        return self.actions_from_outputs(out, vectorized=vectorized), state


class NumpyBankPolicy(SarsaAACPolicy):
    """
    A :class:`SarsaAACPolicy` whose ``A`` outputs are the independent approximators of one numpy bank,
    :attr:`approximators` (a :class:`~sb3_aac.sarsa_aac.approximators.NumpyBank`: torch tensors for save/load, numpy
    on zero-copy views for everything else). Subclasses build the bank and pass it to :meth:`_set_approximators`.
    """

    approximators: NumpyBank

    def _set_approximators(self, bank: NumpyBank) -> None:
        """Adopt ``bank``, which holds :attr:`n_outputs` approximators (one per output column)."""
        self.approximators = bank

    def evaluate(self, obs: np.ndarray) -> tuple[np.ndarray, Any]:
        """See :meth:`SarsaAACPolicy.evaluate`; for weights stored off the CPU the cache is None."""
        obs = obs.reshape(len(obs), -1)
        if self.approximators.obs_mid.device.type == "cpu":
            return self.kernel().forward(obs)
        return self.approximators.evaluate(obs), None

    def kernel(self) -> Kernel[Any]:
        """The bank's numpy kernel on the current parameter storage (CPU only); cached by the bank."""
        return self.approximators.numpy_kernel()

    def rebind(self) -> Kernel[Any]:
        """Rebuild the numpy views, e.g. after assigning ``param.data`` directly."""
        self.approximators.invalidate_kernel()
        return self.approximators.numpy_kernel()

    def scale_outputs(self, columns: list[int], factor: float) -> None:
        self.approximators.scale_outputs(columns, factor)

    def finite_outputs(self) -> np.ndarray:
        return self.approximators.finite_outputs()


class DenseBankPolicy(NumpyBankPolicy):
    """
    The function approximators of Uc-Cetina (2013, Sec. 4.2) in one
    :class:`~sb3_aac.sarsa_aac.approximators.ApproximatorBank`: scaled inputs or Gaussian RBFs per input, then a
    linear or one-hidden-layer tanh head per approximator. :class:`MlpPolicy`, :class:`RbfMlpPolicy` and
    :class:`RbfPolicy` are its presets (the paper's three families; only their defaults differ).

    :param observation_space: A ``Box`` observation space (any shape; it is flattened)
    :param action_space: A parameterized action space (see :mod:`sb3_aac.common.spaces`)
    :param hidden_units: Hidden tanh units of each approximator, or ``None`` for linear approximators
    :param n_rbf: Gaussian RBFs per observation input, or ``None`` to feed the scaled inputs directly
    :param rbf_width: RBF standard deviation in units of the spacing between centres (chosen by us: 1.0,
        the paper gives no value)
    :param obs_bounds: ``(low, high)`` used to scale the inputs to ``[-1, 1]`` and to place the RBF centres
        evenly; defaults to the observation space's bounds. Without RBFs, inputs with infinite bounds are
        passed through unscaled.
    :param rbf_window: Only the Gaussians within this many standard deviations of each input are computed, the
        others are exactly 0, in training, ``predict`` and the exported runtime alike (see
        :class:`~sb3_aac.runtime.forward.BankForward`); ``None`` computes all. The default 5 drops features below
        ``exp(-12.5) = 3.7e-6``, so outputs differ from dense evaluation by less than ``3.7e-6`` times the sum of
        the absolute weights on the dropped features; at 50 RBFs per input it evaluates 13 of them per input.
    """

    approximators: ApproximatorBank

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        hidden_units: int | None = 10,
        n_rbf: int | None = None,
        rbf_width: float = 1.0,
        obs_bounds: tuple[np.ndarray, np.ndarray] | None = None,
        rbf_window: float | None = DEFAULT_RBF_WINDOW,
    ):
        super().__init__(observation_space, action_space, obs_bounds)
        low, high = self.input_bounds()
        self.hidden_units, self.n_rbf, self.rbf_width, self.rbf_window = hidden_units, n_rbf, rbf_width, rbf_window
        if n_rbf is not None and not (np.all(np.isfinite(low)) and np.all(np.isfinite(high))):
            raise ValueError(
                f"The observation space {observation_space} has infinite bounds, so RBF centres cannot be placed: "
                "pass policy_kwargs=dict(obs_bounds=(low, high)) with finite bounds, or use MlpPolicy"
            )
        self._set_approximators(
            ApproximatorBank(
                low, high, self.n_outputs, n_rbf=n_rbf, rbf_width=rbf_width, hidden_units=hidden_units, rbf_window=rbf_window
            )
        )

    @property
    def chunks_lanes(self) -> bool:
        return self.hidden_units is not None

    def _get_constructor_parameters(self) -> dict[str, Any]:
        # Not super()'s: it adds normalize_images, which these policies do not take.
        return dict(
            observation_space=self.observation_space,
            action_space=self.action_space,
            hidden_units=self.hidden_units,
            n_rbf=self.n_rbf,
            rbf_width=self.rbf_width,
            obs_bounds=self.obs_bounds,
            rbf_window=self.rbf_window,
        )


class MlpPolicy(DenseBankPolicy):
    """
    Multilayer perceptrons (Uc-Cetina 2013, Fig. 5): each approximator has one hidden tanh layer over the scaled
    observation. The paper tried 2, 10 and 20 hidden units (2 was the most reliable on dribbling); the default 10
    is ours. Observation inputs with infinite bounds are fed unscaled unless ``obs_bounds`` is given. The arguments
    are :class:`DenseBankPolicy`'s.
    """

    # Half the other families' step: better than 0.1 on the paper env on 1, 16 and 256 lanes, which with the lanes in
    # chunks end within 1 m of each other (docs/sarsa_aac_results.md, "Lane count and the plateau", has the figures).
    default_learning_rate: ClassVar[float] = 0.05
    default_replay_ratio: ClassVar[int] = 2

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        hidden_units: int | None = 10,
        n_rbf: int | None = None,
        rbf_width: float = 1.0,
        obs_bounds: tuple[np.ndarray, np.ndarray] | None = None,
        rbf_window: float | None = DEFAULT_RBF_WINDOW,
    ):
        super().__init__(observation_space, action_space, hidden_units, n_rbf, rbf_width, obs_bounds, rbf_window)


class RbfMlpPolicy(DenseBankPolicy):
    """
    Multilayer perceptrons behind a Gaussian RBF filter layer (Uc-Cetina 2013, Fig. 6): each input feeds
    ``n_rbf`` Gaussians (10 in the paper, the default) and those feed one hidden tanh layer (2, 10 or 20 units in
    the paper; the default 10 is ours). The arguments are :class:`DenseBankPolicy`'s.
    """

    default_replay_ratio: ClassVar[int] = 2

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        hidden_units: int | None = 10,
        n_rbf: int | None = 10,
        rbf_width: float = 1.0,
        obs_bounds: tuple[np.ndarray, np.ndarray] | None = None,
        rbf_window: float | None = DEFAULT_RBF_WINDOW,
    ):
        super().__init__(observation_space, action_space, hidden_units, n_rbf, rbf_width, obs_bounds, rbf_window)


class RbfPolicy(DenseBankPolicy):
    """
    Arrays of Gaussian RBFs with a linear output (Uc-Cetina 2013, Fig. 7), the paper's best family: one array
    of ``n_rbf`` Gaussians per input (10, 30 or 50 in the paper; default 10) and a linear approximator on top
    (``hidden_units=None``). The arguments are :class:`DenseBankPolicy`'s.
    """

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        hidden_units: int | None = None,
        n_rbf: int | None = 10,
        rbf_width: float = 1.0,
        obs_bounds: tuple[np.ndarray, np.ndarray] | None = None,
        rbf_window: float | None = DEFAULT_RBF_WINDOW,
    ):
        super().__init__(observation_space, action_space, hidden_units, n_rbf, rbf_width, obs_bounds, rbf_window)


class TilePolicy(NumpyBankPolicy):
    """
    Tile coding over groups of inputs with a linear output (:mod:`sb3_aac.sarsa_aac.tile_coding`; not in the paper):
    features that combine inputs, so values such as "heading relative to the target direction" are representable,
    still closed-form and sparse (training and decisions cost ``O(n_groups * n_tilings)`` per approximator).
    The default groups, every input and every pair of inputs, need no knowledge of the inputs. Learns with
    eligibility traces when SarsaAAC's ``trace_lambda > 0`` (as :class:`DeepPolicy` does).

    :param observation_space: A ``Box`` observation space with finite bounds (or give ``obs_bounds``)
    :param action_space: A parameterized action space (see :mod:`sb3_aac.common.spaces`)
    :param tile_groups: Groups of (flattened) input indices tiled jointly, e.g. ``[(0,), (1,), (0, 1)]``; None for
        every input and every pair
    :param tiles_per_input: Tiles across each input's range per tiling (8, chosen by us)
    :param n_tilings: Offset tilings per group (8, chosen by us)
    :param obs_bounds: ``(low, high)`` where the grids start and end; defaults to the observation space's bounds
    """

    approximators: TileBank

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        tile_groups: list[tuple[int, ...]] | None = None,
        tiles_per_input: int = 8,
        n_tilings: int = 8,
        obs_bounds: tuple[np.ndarray, np.ndarray] | None = None,
    ):
        super().__init__(observation_space, action_space, obs_bounds)
        low, high = self.input_bounds()
        if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high))):
            raise ValueError(
                f"The observation space {observation_space} has infinite bounds, so tiles cannot be placed: "
                "pass policy_kwargs=dict(obs_bounds=(low, high)) with finite bounds"
            )
        self.tile_groups, self.tiles_per_input, self.n_tilings = tile_groups, tiles_per_input, n_tilings
        self._set_approximators(TileBank(low, high, self.n_outputs, tile_groups, tiles_per_input, n_tilings))

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return dict(
            observation_space=self.observation_space,
            action_space=self.action_space,
            tile_groups=self.tile_groups,
            tiles_per_input=self.tiles_per_input,
            n_tilings=self.n_tilings,
            obs_bounds=self.obs_bounds,
        )


class DeepPolicy(NumpyBankPolicy):
    """
    Deep networks trained online, one sample at a time (:mod:`sb3_aac.sarsa_aac.deep`; not in the paper): one
    feed-forward network for the action-type actor (K outputs), one for the parameter actor (P outputs) and one for
    the critic, each with the hidden layers ``linear -> layer norm -> leaky ReLU`` of Elsayed, Vasan & Mahmood 2024
    (arXiv 2410.14606), sparse initialisation, online observation normalisation and overshooting-bounded (ObGD)
    steps, with eligibility traces when SarsaAAC's ``trace_lambda > 0`` (the paper uses 0.8).

    :param observation_space: A ``Box`` observation space (any shape; it is flattened; infinite bounds are fine)
    :param action_space: A parameterized action space (see :mod:`sb3_aac.common.spaces`)
    :param net_arch: hidden layer sizes of each network, each in ``[1, 4096]`` (default two of 64: the paper used
        128, 64 keeps one exported decision within 10 us)
    :param sparsity: share of zero input weights of each unit at initialisation, in ``[0, 1)`` (0.9, the paper's)
    :param normalize_obs: normalise each input by the running mean and standard deviation of the training
        observations (the paper's); if False, inputs are scaled from ``obs_bounds`` to ``[-1, 1]``
    :param kappa: ObGD's overshooting factor, a finite number ``> 0`` (2.0, the paper's value for value networks)
    :param obs_bounds: ``(low, high)`` for the scaling before the first observations (and always without
        ``normalize_obs``); defaults to the observation space's bounds
    """

    approximators: DeepBank
    # SarsaAAC's rates are ObGD's step size alpha here; its figures in docs/sarsa_aac_results.md were measured with 0.5.
    default_learning_rate: ClassVar[float] = 0.5

    def __init__(
        self,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        net_arch: tuple[int, ...] | list[int] = (64, 64),
        sparsity: float = DEFAULT_SPARSITY,
        normalize_obs: bool = True,
        kappa: float = 2.0,
        obs_bounds: tuple[np.ndarray, np.ndarray] | None = None,
    ):
        super().__init__(observation_space, action_space, obs_bounds)
        low, high = self.input_bounds()
        if not isinstance(normalize_obs, (bool, np.bool_)):
            raise ValueError(f"normalize_obs must be True or False, got {normalize_obs!r}")
        self.net_arch, self.sparsity, self.normalize_obs, self.kappa = (
            check_net_arch(net_arch),
            sparsity,
            bool(normalize_obs),
            kappa,
        )
        self._set_approximators(
            DeepBank(low, high, self.n_types, self.n_params, self.net_arch, sparsity, self.normalize_obs, kappa)
        )

    @property
    def chunks_lanes(self) -> bool:
        return True  # even with net_arch=[]: a chunk's steps are summed (sb3_aac.sarsa_aac.deep, "Lanes")

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return dict(
            observation_space=self.observation_space,
            action_space=self.action_space,
            net_arch=self.net_arch,
            sparsity=self.sparsity,
            normalize_obs=self.normalize_obs,
            kappa=self.kappa,
            obs_bounds=self.obs_bounds,
        )
