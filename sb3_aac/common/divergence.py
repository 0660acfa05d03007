"""The error every algorithm of this package raises when training produces a non-finite value."""

from __future__ import annotations


def divergence_error(algorithm: str, what: str, timestep: int, remedy: str, restored: str | None = None) -> FloatingPointError:
    """
    The ``FloatingPointError`` for a diverged training run, worded the same for every algorithm::

        <algorithm> diverged: <what> became non-finite (nan or inf) by timestep <timestep>[; <restored>]. <remedy>;
        also check that the env returns finite rewards and observations.

    :param algorithm: the algorithm's class name
    :param what: what became non-finite, e.g. ``"the Q network's loss"``
    :param timestep: the algorithm's ``num_timesteps`` when it was found
    :param remedy: what to change, naming the settings now, e.g. ``"Lower the learning rates (learning_rate=0.5)"``
    :param restored: what happened to the weights, for an algorithm that restores them (None: nothing is said)
    """
    state = "" if restored is None else f"; {restored}"
    return FloatingPointError(
        f"{algorithm} diverged: {what} became non-finite (nan or inf) by timestep {timestep}{state}. {remedy}; "
        "also check that the env returns finite rewards and observations."
    )
