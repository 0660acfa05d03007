"""Top-down view of the dribbling scene: plain numbers in, pixels out.

Independent of the physics: the env fills a :class:`RenderFrame` and :class:`DribbleRenderer` draws it with
pygame (imported lazily; install it with ``pip install "sb3-aac[render]"``).  Conventions are the server's
monitor (``docs/physics.md`` §8): x to the right, +y *down* the screen, and a positive body
angle turns clockwise on screen.  The camera follows the player horizontally,
or stays where it is told.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium.error import DependencyNotInstalled

RENDER_MODES = ("human", "rgb_array")

# Pitch geometry in metres (docs/physics.md §8).
HALF_LENGTH, HALF_WIDTH = 52.5, 34.0
CENTRE_CIRCLE_R = 9.15
PENALTY_LENGTH, PENALTY_HALF_WIDTH = 16.5, 40.32 / 2
GOAL_AREA_LENGTH, GOAL_AREA_HALF_WIDTH = 5.5, 18.32 / 2
GOAL_HALF_WIDTH, GOAL_DEPTH = 14.02 / 2, 2.44

OUTSIDE = (24, 94, 32)
GRASS = (40, 130, 50)
GRID = (58, 148, 66)
LINE = (240, 240, 240)
GOAL = (120, 120, 130)
BALL = (255, 255, 255)
BALL_EDGE = (20, 20, 20)
PLAYER = (250, 200, 30)
PLAYER_EDGE = (60, 40, 0)
KICKABLE = (255, 235, 120)
CAPTION = (255, 255, 255)


def _empty_trail() -> np.ndarray:
    return np.zeros((0, 2))


@dataclass
class RenderFrame:
    """What one picture shows (metres, degrees)."""

    player_xy: tuple[float, float]
    body_deg: float
    player_size: float
    kickable_area: float
    ball_xy: tuple[float, float]
    ball_size: float
    trail: np.ndarray = field(default_factory=_empty_trail)  # (k, 2) recent ball positions, oldest first
    player_trail: np.ndarray = field(default_factory=_empty_trail)  # (k, 2) recent player positions, oldest first
    caption: str = ""  # e.g. "type 3 | step 17/35 | 12.3 m"


def _import_pygame() -> Any:
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    try:
        import pygame
    except ImportError as e:
        raise DependencyNotInstalled('pygame is not installed; run `pip install "sb3-aac[render]"`') from e
    return pygame


class DribbleRenderer:
    """Draw :class:`RenderFrame` s to a window (``"human"``) or to arrays (``"rgb_array"``); the view is
    ``view_width_m`` wide and follows the player, or stays centred on ``view_centre`` (m) when one is given."""

    def __init__(
        self,
        render_mode: str,
        width: int = 720,
        height: int = 400,
        view_width_m: float = 24.0,
        fps: int = 10,
        view_centre: tuple[float, float] | None = None,
    ) -> None:
        if render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be one of {list(RENDER_MODES)}, got {render_mode!r}")
        if width <= 0 or height <= 0 or view_width_m <= 0:
            raise ValueError("width, height and view_width_m must be positive")
        self.render_mode = render_mode
        self.width, self.height, self.fps = int(width), int(height), int(fps)
        self.scale = self.width / float(view_width_m)  # pixels per metre
        self._pg: Any = None
        self._canvas: Any = None
        self._window: Any = None
        self._clock: Any = None
        self._font: Any = None
        self._small_font: Any = None
        self._view_centre = view_centre
        self._camera = (0.0, 0.0) if view_centre is None else view_centre

    # --- set-up -------------------------------------------------------------------------------

    def _setup(self) -> None:
        pg = self._pg = _import_pygame()
        self._canvas = pg.Surface((self.width, self.height))  # no display needed for rgb_array
        try:
            pg.font.init()
            self._font = pg.font.Font(None, 22)
            self._small_font = pg.font.Font(None, 16)
        except Exception:  # font support is optional: skip the text
            self._font = self._small_font = None
        if self.render_mode == "human":
            pg.display.init()
            self._window = pg.display.set_mode((self.width, self.height))
            pg.display.set_caption("RoboCup dribble")
            self._clock = pg.time.Clock()

    # --- geometry -----------------------------------------------------------------------------

    def _px(self, x: float, y: float) -> tuple[int, int]:
        cx, cy = self._camera
        return round(self.width / 2 + (x - cx) * self.scale), round(self.height / 2 + (y - cy) * self.scale)

    def _r(self, metres: float, minimum: int = 1) -> int:
        return max(minimum, round(metres * self.scale))

    def _follow(self, frame: RenderFrame) -> None:
        """Centre on the player's x; keep y = 0 in view unless the player would leave it."""
        px, py = (float(v) for v in frame.player_xy)
        half_h = self.height / 2 / self.scale
        margin = min(3.0, half_h / 2)
        cy = float(np.clip(0.0, py - half_h + margin, py + half_h - margin))
        self._camera = (px, cy)

    # --- drawing ------------------------------------------------------------------------------

    def _draw_pitch(self) -> None:
        pg, s = self._pg, self._canvas
        s.fill(OUTSIDE)
        left, top = self._px(-HALF_LENGTH, -HALF_WIDTH)
        right, bottom = self._px(HALF_LENGTH, HALF_WIDTH)
        pg.draw.rect(s, GRASS, pg.Rect(left, top, right - left, bottom - top))
        # light grid every 5 m and a labelled tick every 1 m along the bottom, so progress is visible
        cx = self._camera[0]
        half_w = self.width / 2 / self.scale
        for xm in range(int(np.floor(cx - half_w)), int(np.ceil(cx + half_w)) + 1):
            x = self._px(xm, 0)[0]
            if xm % 5 == 0:
                pg.draw.line(s, GRID, (x, 0), (x, self.height), 1)
            tick = 8 if xm % 5 == 0 else 4
            pg.draw.line(s, LINE, (x, self.height - tick), (x, self.height), 1)
            if xm % 10 == 0 and self._small_font is not None:
                label = self._small_font.render(f"{xm} m", True, LINE)
                s.blit(label, (x + 3, self.height - 8 - label.get_height()))
        w = 2
        pg.draw.rect(s, LINE, pg.Rect(left, top, right - left, bottom - top), w)  # touch and goal lines
        pg.draw.line(s, LINE, self._px(0, -HALF_WIDTH), self._px(0, HALF_WIDTH), w)
        pg.draw.circle(s, LINE, self._px(0, 0), self._r(CENTRE_CIRCLE_R), w)
        pg.draw.circle(s, LINE, self._px(0, 0), 3)
        for side in (-1, 1):
            goal_x = side * HALF_LENGTH
            self._rect(goal_x, goal_x + side * GOAL_DEPTH, -GOAL_HALF_WIDTH, GOAL_HALF_WIDTH, 0, GOAL)
            self._rect(goal_x, goal_x + side * GOAL_DEPTH, -GOAL_HALF_WIDTH, GOAL_HALF_WIDTH, w)
            self._rect(goal_x, goal_x - side * PENALTY_LENGTH, -PENALTY_HALF_WIDTH, PENALTY_HALF_WIDTH, w)
            self._rect(goal_x, goal_x - side * GOAL_AREA_LENGTH, -GOAL_AREA_HALF_WIDTH, GOAL_AREA_HALF_WIDTH, w)

    def _rect(self, x0: float, x1: float, y0: float, y1: float, width: int, colour: tuple[int, int, int] = LINE) -> None:
        """Axis-aligned rectangle in metres; width 0 fills it."""
        (ax, ay), (bx, by) = self._px(min(x0, x1), y0), self._px(max(x0, x1), y1)
        self._pg.draw.rect(self._canvas, colour, self._pg.Rect(ax, ay, bx - ax, by - ay), width)

    def _draw_trail(
        self, overlay: Any, points: np.ndarray, colour: tuple[int, int, int], radius: int, alpha: tuple[int, int]
    ) -> None:
        """Dots from oldest (alpha[0]) to newest (alpha[1])."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        for i, (x, y) in enumerate(pts):
            a = alpha[1] if len(pts) == 1 else round(alpha[0] + (alpha[1] - alpha[0]) * i / (len(pts) - 1))
            self._pg.draw.circle(overlay, (*colour, a), self._px(x, y), radius)

    def _draw_objects(self, frame: RenderFrame) -> None:
        pg, s = self._pg, self._canvas
        overlay = pg.Surface((self.width, self.height), pg.SRCALPHA)
        self._draw_trail(overlay, frame.player_trail, PLAYER, max(2, self._r(frame.player_size) // 3), (20, 90))
        self._draw_trail(overlay, frame.trail, BALL, self._r(frame.ball_size, 2), (25, 170))
        s.blit(overlay, (0, 0))

        centre = self._px(*frame.player_xy)
        pg.draw.circle(s, KICKABLE, centre, self._r(frame.kickable_area, 4), 1)
        radius = self._r(frame.player_size, 4)
        pg.draw.circle(s, PLAYER, centre, radius)
        pg.draw.circle(s, PLAYER_EDGE, centre, radius, 1)
        a = np.deg2rad(frame.body_deg)  # (cos a, sin a) with +y down: clockwise on screen
        reach = max(radius + 6, self._r(frame.kickable_area))
        tip = (round(centre[0] + reach * np.cos(a)), round(centre[1] + reach * np.sin(a)))
        pg.draw.line(s, PLAYER_EDGE, centre, tip, 2)

        ball = self._px(*frame.ball_xy)
        ball_r = self._r(frame.ball_size, 3)
        pg.draw.circle(s, BALL, ball, ball_r)
        pg.draw.circle(s, BALL_EDGE, ball, ball_r + 1, 1)

    def _draw_caption(self, caption: str) -> None:
        if not caption or self._font is None:
            return
        text = self._font.render(caption, True, CAPTION)
        bar = self._pg.Surface((self.width, text.get_height() + 8), self._pg.SRCALPHA)
        bar.fill((0, 0, 0, 120))
        self._canvas.blit(bar, (0, 0))
        self._canvas.blit(text, (8, 4))

    # --- public -------------------------------------------------------------------------------

    def render(self, frame: RenderFrame) -> np.ndarray | None:
        """Draw ``frame``: an ``(height, width, 3)`` uint8 array for ``"rgb_array"``, None for ``"human"``."""
        if self._pg is None:
            self._setup()
        if self._view_centre is None:
            self._follow(frame)
        self._draw_pitch()
        self._draw_objects(frame)
        self._draw_caption(frame.caption)
        if self.render_mode == "rgb_array":
            return np.ascontiguousarray(np.transpose(self._pg.surfarray.array3d(self._canvas), (1, 0, 2)), dtype=np.uint8)
        self._pg.event.pump()
        self._window.blit(self._canvas, (0, 0))
        self._pg.display.flip()
        self._clock.tick(self.fps)
        return None

    def close(self) -> None:
        """Close the window (if any); the renderer can be used again afterwards."""
        if self._window is not None:
            self._pg.display.quit()
        self._pg = self._canvas = self._window = self._clock = self._font = self._small_font = None
