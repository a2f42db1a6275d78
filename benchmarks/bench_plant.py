#!/usr/bin/env python3
"""
Real-time factor of the simulator's engines: simulated seconds per second.

Each engine's plant (``builtin``: :class:`plant.Plant`; ``mujoco``:
:class:`mujoco_plant.MujocoPlant`) makes ``--seconds`` of simulated motion
at 1 kHz and 2 kHz under the force that holds the platform at home (what
the ``simulator`` node's step does, without ROS); printed: the simulated
seconds per wall-clock second and the time per step.

Usage: .venv/bin/python benchmarks/bench_plant.py [--seconds S]
"""

import argparse
import time

from orthoglide_ros.model import mechanics, mujoco_plant
from orthoglide_ros.model.plant import Plant
from orthoglide_ros.model.robot import Robot


def main():
    """Time both engines at both rates; print a table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--seconds', type=float, default=2.0)
    args = parser.parse_args()
    robot = Robot()
    hold = mechanics.solve(robot, (0.0,) * 3).force
    engines = {'builtin': Plant}
    if not mujoco_plant.unavailable():
        engines['mujoco'] = mujoco_plant.MujocoPlant
    print(f'{"engine":>8} {"rate (Hz)":>10} {"real-time factor":>17} '
          f'{"us per step":>12}')
    for name, engine in engines.items():
        for rate in (1000.0, 2000.0):
            plant = engine(robot, force_limit=1000.0)
            steps = round(args.seconds * rate)
            start = time.perf_counter()
            for _ in range(steps):
                plant.step(hold, 1.0 / rate)
            wall = time.perf_counter() - start
            print(f'{name:>8} {rate:>10.0f} {args.seconds / wall:>16.1f}x '
                  f'{wall / steps * 1e6:>12.1f}')


if __name__ == '__main__':
    main()
