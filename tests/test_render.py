"""The pitch renderer: plain numbers in, pixels out."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from gymnasium.error import DependencyNotInstalled

pytest.importorskip("pygame")

from robocup_dribble.render import BALL, LINE, PLAYER_EDGE, DribbleRenderer, RenderFrame


def frame(player=(10.0, 0.0), ball=(11.0, 2.0), body=0.0, **kw) -> RenderFrame:
    kw.setdefault("caption", "type 3 | step 17/35 | 12.3 m")
    return RenderFrame(
        player_xy=player, body_deg=body, player_size=0.3, kickable_area=1.085, ball_xy=ball, ball_size=0.085, **kw
    )


@pytest.fixture
def renderer():
    r = DribbleRenderer("rgb_array")
    yield r
    r.close()


def test_rgb_array_shape_and_dtype(renderer):
    img = renderer.render(frame(trail=np.array([[8.0, 1.0], [9.0, 1.5]]), player_trail=np.array([[9.0, 0.0]])))
    assert img.shape == (400, 720, 3) and img.dtype == np.uint8
    small = DribbleRenderer("rgb_array", width=160, height=90).render(frame(caption=""))
    assert small.shape == (90, 160, 3)


def test_ball_is_drawn_where_expected(renderer):
    # 720 px show 24 m: 30 px/m; the camera centres the player's x, y = 0 stays at the middle row
    img = renderer.render(frame(player=(10.0, 0.0), ball=(11.0, 2.0)))
    col, row = 360 + 30, 200 + 2 * 30
    assert tuple(img[row, col]) == BALL
    elsewhere = renderer.render(frame(player=(10.0, 0.0), ball=(8.0, -3.0)))
    assert not np.all(elsewhere[row - 2 : row + 3, col - 2 : col + 3] == BALL)
    assert tuple(elsewhere[200 - 90, 360 - 60]) == BALL


def test_camera_follows_the_player(renderer):
    a = renderer.render(frame(player=(0.0, 0.0), ball=(0.5, 0.0)))
    b = renderer.render(frame(player=(3.0, 0.0), ball=(3.5, 0.0)))
    assert not np.array_equal(a, b)
    row = 320  # 4 m below the centre line: only the halfway line crosses it
    assert tuple(a[row, 360]) == LINE
    assert tuple(b[row, 360 - 90]) == LINE and tuple(b[row, 360]) != LINE


def test_positive_body_angle_turns_clockwise_on_screen(renderer):
    below = (200 + 15, 360 + 0)  # +y is down: body 90 points down the screen
    down = renderer.render(frame(player=(10.0, 0.0), ball=(14.0, -5.0), body=90.0, caption=""))
    up = renderer.render(frame(player=(10.0, 0.0), ball=(14.0, -5.0), body=-90.0, caption=""))
    assert tuple(down[below]) == PLAYER_EDGE
    assert tuple(up[below]) != PLAYER_EDGE
    assert tuple(up[200 - 15, 360]) == PLAYER_EDGE


def test_tiny_objects_stay_visible():
    r = DribbleRenderer("rgb_array", view_width_m=600.0)  # 1.2 px/m: the ball would be 0.1 px
    img = r.render(frame(player=(0.0, 20.0), ball=(25.0, 25.0), caption=""))
    assert np.all(img == BALL, axis=-1).sum() >= 9


def test_invalid_mode_raises():
    with pytest.raises(ValueError, match=r"human.*rgb_array"):
        DribbleRenderer("ansi")


def test_human_mode_with_dummy_video_driver(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    r = DribbleRenderer("human", fps=1000)
    try:
        assert r.render(frame()) is None
        assert r.render(frame(player=(11.0, 0.5))) is None
    finally:
        r.close()


def test_missing_pygame_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "pygame", None)  # makes `import pygame` fail
    with pytest.raises(DependencyNotInstalled, match=r"sb3-aac\[render\]"):
        DribbleRenderer("rgb_array").render(frame())
