"""What every hybrid domain shares: :meth:`~EpisodicEnv.step` only inside an episode, and no rendering."""

from __future__ import annotations

from typing import Any, Generic, TypeVar

import gymnasium as gym
from gymnasium.error import ResetNeeded

ObsT = TypeVar("ObsT")


class EpisodicEnv(gym.Env[ObsT, tuple[Any, ...]], Generic[ObsT]):
    """
    A domain's rules of play, as robocup_dribble's env keeps them: :meth:`step` before the first :meth:`reset`, or
    after the episode ended (terminated or truncated), raises Gymnasium's ``ResetNeeded`` and changes nothing; the
    domain's own step is :meth:`_step`. No rendering: ``render_mode`` must be None, and :meth:`render` says so.
    """

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012  (Gymnasium declares it so)
    _running: bool | None = None  # None before the first reset, then whether the episode goes on

    def _check_render_mode(self, render_mode: str | None) -> None:
        if render_mode is not None:
            raise ValueError(
                f"{type(self).__name__} draws nothing: render_mode must be None (it has no render modes), got {render_mode!r}"
            )

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[ObsT, dict[str, Any]]:
        """Seed the env (Gymnasium's ``reset``) and start an episode; the domain's ``reset`` then sets it up."""
        super().reset(seed=seed)
        self._running = True
        return None  # type: ignore[return-value]  # the domain's reset returns the first observation

    def step(self, action: tuple[Any, ...]) -> tuple[ObsT, float, bool, bool, dict[str, Any]]:
        if self._running is None:
            raise ResetNeeded("Call reset() before step(): the episode has not started")
        if not self._running:
            raise ResetNeeded("Call reset() before step(): the episode has ended (terminated or truncated)")
        out = self._step(action)
        self._running = not (out[2] or out[3])
        return out

    def _step(self, action: tuple[Any, ...]) -> tuple[ObsT, float, bool, bool, dict[str, Any]]:
        raise NotImplementedError

    def render(self) -> None:
        raise NotImplementedError(f"{type(self).__name__} draws nothing: it has no render modes (render_mode=None only)")
