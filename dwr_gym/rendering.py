"""Pygame drawing of one robot, its goal, its trail and the time left to T_con."""

from __future__ import annotations

import math
import os
import sys
from typing import Any

import numpy as np
from gymnasium.error import DependencyNotInstalled
from numpy.typing import NDArray

from dwr_gym.params import EnvParams
from dwr_gym.state import TaskState

BODY_RADIUS = 0.05  # [m] drawn size of the robot
WHEEL_LENGTH = 0.045  # [m]
WHEEL_WIDTH = 0.016  # [m]


def headless() -> bool:
    """Whether there is no display a window could open on (Linux and BSD without X11 or Wayland)."""
    unix = sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd"))
    return unix and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class Renderer:
    """Draws frames for ``render_mode`` 'rgb_array' or 'human' (a window). Pygame is imported lazily."""

    def __init__(self, render_mode: str, fps: int, size: int = 480) -> None:
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        if render_mode == "human" and headless():
            # No display to open a window on: SDL would probe its video drivers and print alarming errors
            # ("XDG_RUNTIME_DIR is invalid or not set"), as when Gymnasium's check_env tries every render mode.
            os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        try:
            import pygame
        except ImportError as error:
            raise DependencyNotInstalled(
                'pygame is not installed; rendering needs it: pip install "dwr-gym[render]" (or pip install pygame)'
            ) from error
        self._pg: Any = pygame
        self.render_mode = render_mode
        self.fps = fps
        self.size = size
        pygame.font.init()
        if render_mode == "human":
            pygame.display.init()
            pygame.display.set_caption("dwr-gym")
            self._window = pygame.display.set_mode((size, size))
            self._clock = pygame.time.Clock()
        self._canvas = pygame.Surface((size, size))
        self._font = pygame.font.Font(None, 22)

    def __getstate__(self) -> dict[str, Any]:
        """The settings only: pygame's module and surfaces cannot be pickled, so a copy sets them up anew."""
        return {"render_mode": self.render_mode, "fps": self.fps, "size": self.size}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(**state)  # type: ignore[misc]

    def draw(
        self,
        pose: tuple[float, float, float],
        goal: tuple[float, float, float],
        trail: list[tuple[float, float]],
        time: float,
        T_con: float,
        tolerance: float,
    ) -> NDArray[np.uint8] | None:
        """Draw one frame; returns it as an (H, W, 3) uint8 array in 'rgb_array' mode."""
        pg = self._pg
        start = trail[0] if trail else pose[:2]
        center = ((start[0] + goal[0]) / 2.0, (start[1] + goal[1]) / 2.0)
        half = max(math.hypot(start[0] - goal[0], start[1] - goal[1]) / 2.0 + 0.3, 0.5)
        scale = self.size / (2.0 * half)

        def to_px(x: float, y: float) -> tuple[int, int]:
            return int(self.size / 2 + (x - center[0]) * scale), int(self.size / 2 - (y - center[1]) * scale)

        def rotated_rect(cx: float, cy: float, heading: float, length: float, width: float) -> list[tuple[int, int]]:
            c, s = math.cos(heading), math.sin(heading)
            corners = [
                (length / 2, width / 2),
                (-length / 2, width / 2),
                (-length / 2, -width / 2),
                (length / 2, -width / 2),
            ]
            return [to_px(cx + a * c - b * s, cy + a * s + b * c) for a, b in corners]

        canvas = self._canvas
        canvas.fill((250, 250, 250))
        # goal pose: tolerance circle and heading arrow
        gx, gy, gpsi = goal
        pg.draw.circle(canvas, (120, 200, 120), to_px(gx, gy), max(int(tolerance * scale), 3), 0)
        pg.draw.line(
            canvas, (40, 140, 40), to_px(gx, gy), to_px(gx + 0.12 * math.cos(gpsi), gy + 0.12 * math.sin(gpsi)), 3
        )
        if len(trail) > 1:
            pg.draw.lines(canvas, (90, 120, 220), False, [to_px(*p) for p in trail], 2)
        # robot: wheels on both sides of the axle, body, heading
        x, y, psi = pose
        body_px = max(int(BODY_RADIUS * scale), 6)
        for side in (1.0, -1.0):
            wx, wy = x - side * BODY_RADIUS * math.sin(psi), y + side * BODY_RADIUS * math.cos(psi)
            pg.draw.polygon(canvas, (30, 30, 30), rotated_rect(wx, wy, psi, WHEEL_LENGTH, WHEEL_WIDTH))
        pg.draw.circle(canvas, (220, 110, 40), to_px(x, y), body_px)
        tip = to_px(x + 1.3 * BODY_RADIUS * math.cos(psi), y + 1.3 * BODY_RADIUS * math.sin(psi))
        pg.draw.line(canvas, (20, 20, 20), to_px(x, y), tip, 3)
        left = T_con - time
        text = (
            f"t = {time:5.2f} s   T_con - t = {left:+6.2f} s"
            if left >= 0
            else f"t = {time:5.2f} s   late by {-left:.2f} s"
        )
        colour = (20, 20, 20) if left >= 0 else (200, 30, 30)
        canvas.blit(self._font.render(text, True, colour), (10, 10))

        if self.render_mode == "human":
            self._window.blit(canvas, (0, 0))
            pg.event.pump()
            pg.display.flip()
            self._clock.tick(self.fps)
            return None
        return np.transpose(np.array(pg.surfarray.pixels3d(canvas), dtype=np.uint8), (1, 0, 2))

    def draw_robot(
        self, state: TaskState, i: int, trail: list[tuple[float, float]], params: EnvParams
    ) -> NDArray[np.uint8] | None:
        """Draw robot ``i`` of a batched :class:`~dwr_gym.core.TaskState`."""

        def at(value: Any) -> float:
            return float(value if np.ndim(value) == 0 else value[i])

        x, y, psi = (at(v) for v in state.world_pose())
        goal = (at(state.goal_x), at(state.goal_y), at(state.goal_psi))
        time = at(state.step_count) * params.dt
        return self.draw((x, y, psi), goal, trail, time, params.T_con, params.goal_tolerance)

    def close(self) -> None:
        """Close the window, if any."""
        if self.render_mode == "human":
            self._pg.display.quit()
