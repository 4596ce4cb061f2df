# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Live demo: the node, a bag player and a monitor, over DDS on this machine.

``make demo`` runs ``gyro_denoiser`` (shipped EuRoC model) as its own process, plays the
bundled EuRoC test-sequence sample into ``imu/data_raw`` in real time, and monitors
``imu/attitude`` against the ground truth stored in the same bag. As the recording
plays it prints the attitude error of the node beside the raw gyro and the calibrated
IMU a user would otherwise integrate (both computed here, by the node's own numpy
engine for the calibration), then writes a plot of all three. Every trajectory starts
from the ground truth at the node's first output (the node's own start is
gravity-aligned with yaw 0, a constant world rotation the monitor removes), the
convention of ``denoise-imu eval``.
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path
import signal
import subprocess
import sys
import threading
import time

from geometry_msgs.msg import QuaternionStamped
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation

from .core.errors import DatasetError, DenoiseError, OptionError
from .core.metrics import error_components, integrate
from .core.modelfile import read_model_file, shipped_models
from .core.msgs import stamp_ns
from .core.records import Sequence
from .data.load import load_sequence
from .evaluation.plots import plot_errors
from .runtime.node import shutdown_rclpy
from .runtime.player import Player, read_imu_messages
from .runtime.streaming import StreamingCorrector

SAMPLE = Path(__file__).parent / 'sample' / 'euroc_V1_03_90s'


def _errors(seq: Sequence, stamps: np.ndarray, quats: np.ndarray,
            calibrated: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, dict[str, tuple]]:
    """Time, trusted stamps and (angle, tilt, yaw) errors per method at the node's stamps."""
    idx = np.searchsorted(seq.stamp_ns, stamps)
    keep = (idx < len(seq)) & (seq.stamp_ns[np.minimum(idx, len(seq) - 1)] == stamps)
    idx, quats = idx[keep], quats[keep]
    if not len(idx):
        raise DatasetError(f'{seq.name}: none of the attitudes received has a stamp of its '
                           'IMU samples')
    gt = Rotation.from_quat(seq.gt_quat[idx])
    node = Rotation.from_quat(quats)
    node = (gt[0] * node[0].inv()) * node  # same start as the ground truth
    first = idx[0]
    gyros = {'raw gyro': seq.imu[:, :3]}
    if calibrated is not None:
        gyros['calibrated IMU'] = calibrated
    errors = {label: error_components(integrate(seq.gt_quat[first], g[first:-1],
                                                seq.dt[first:])[idx - first], gt)
              for label, g in gyros.items()}
    errors['gyro_denoiser imu/attitude'] = error_components(node, gt)
    t = (seq.stamp_ns[idx] - seq.stamp_ns[first]) * 1e-9
    return t, seq.gt_valid[idx], errors


def _calibrated(model: str, imu: np.ndarray) -> np.ndarray | None:
    """Return the gyro of ``<dataset>_calibrated``, the model's calibrated IMU, if shipped."""
    name = f'{read_model_file(model).meta.dataset}_calibrated'
    if name not in shipped_models():
        return None
    calib = read_model_file(name)
    return StreamingCorrector(calib.config, calib.arrays).process(imu)


def main(argv: list[str] | None = None) -> int:
    """Run the live demo; returns the node's exit status, 1 on an error, or 0."""
    try:
        return _demo(argv)
    except DenoiseError as err:
        print(f'denoise-imu-demo: error: {err}', file=sys.stderr)
        return 1


def _demo(argv: list[str] | None) -> int:
    parser = argparse.ArgumentParser(prog='denoise-imu-demo', description=__doc__.split('\n')[1])
    parser.add_argument('--model', default='euroc')
    parser.add_argument('--bag', default=str(SAMPLE))
    parser.add_argument('--rate', type=float, default=1.0, help='playback speed factor')
    parser.add_argument('--seconds', type=float, help='play only this much of the bag')
    parser.add_argument('--out', default='demo_out')
    args = parser.parse_args(argv)
    if not (math.isfinite(args.rate) and args.rate > 0):
        raise OptionError(f'--rate {args.rate:g}: playback rate must be a positive number')
    if args.seconds is not None and not (math.isfinite(args.seconds) and args.seconds > 0):
        raise OptionError(f'--seconds {args.seconds:g}: must be a positive number')
    seq = load_sequence(args.bag)
    calibrated = _calibrated(args.model, seq.imu)
    messages = read_imu_messages(args.bag)
    if args.seconds is not None:
        t0 = stamp_ns(messages[0].header)
        messages = [m for m in messages
                    if (stamp_ns(m.header) - t0) * 1e-9 < args.seconds]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    rclpy.init()
    received: list[tuple[int, tuple[float, ...]]] = []
    monitor = rclpy.create_node('attitude_monitor')
    monitor.create_subscription(
        QuaternionStamped, 'imu/attitude',
        lambda m: received.append((stamp_ns(m.header),
                                   (m.quaternion.x, m.quaternion.y, m.quaternion.z,
                                    m.quaternion.w))),
        QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE))
    executor = SingleThreadedExecutor()
    executor.add_node(monitor)
    player = node_proc = None
    try:
        player = Player(messages, rate=args.rate)
        node_proc = subprocess.Popen(
            [sys.executable, '-m', 'denoise_imu_ros.runtime.node', '--ros-args', '-p',
             f'model:={args.model}', '-p', 'fixed_frame:=world', '--log-level', 'warn'],
            env=dict(os.environ))
        print(f'waiting for gyro_denoiser (model {args.model}) ...', flush=True)
        while not player.has_subscribers() or monitor.count_publishers(
                'imu/attitude') == 0:
            if node_proc.poll() is not None:
                return node_proc.returncode or 1
            executor.spin_once(timeout_sec=0.1)
        # Matching is seen from this side first; give the node's writers time to match the
        # monitor too, or its first (reliable) outputs go nowhere.
        settle = time.monotonic() + 1.0
        while time.monotonic() < settle:
            executor.spin_once(timeout_sec=0.05)
        done = threading.Event()
        threading.Thread(target=lambda: (sum(1 for _ in player.play()), done.set()),
                         daemon=True).start()
        print(f'playing {len(messages)} IMU messages of {Path(args.bag).name} '
              f'at {args.rate:g}x', flush=True)
        print(f'{"time":>7s}  {"raw gyro":>9s}  {"calibrated":>10s}  {"denoised":>9s}   '
              'attitude error vs ground truth (deg)')
        next_report = 10.0
        quiet_since = None
        while True:
            executor.spin_once(timeout_sec=0.05)
            if len(received) > 1:
                elapsed = (received[-1][0] - received[0][0]) * 1e-9
                if elapsed >= next_report:
                    t, _, errors = _errors(seq, *map(np.array, zip(*received)), calibrated)
                    print(f'{t[-1]:6.1f}s  ' + '  '.join(
                        f'{e[0][-1]:9.2f}' for e in errors.values()), flush=True)
                    next_report += 10.0
            if node_proc.poll() is not None:
                raise DenoiseError(f'gyro_denoiser stopped (exit {node_proc.returncode}) '
                                   f'after {len(received)} attitudes')
            if done.is_set():
                quiet_since = quiet_since or time.monotonic()
                if len(received) >= len(messages) or time.monotonic() - quiet_since > 2.0:
                    break
        if not received:
            raise DenoiseError('no attitude received from gyro_denoiser')
        stamps, quats = map(np.array, zip(*received))
        t, valid, errors = _errors(seq, stamps, quats, calibrated)
        print(f'\n{len(received)}/{len(messages)} samples corrected live over DDS; '
              f'attitude error over {t[-1]:.0f} s (RMS / final, deg):')
        for label, (angle, _, _) in errors.items():
            rms = float(np.sqrt(np.mean(angle[valid] ** 2)))
            print(f'  {label:27s}: {rms:7.2f} / {angle[-1]:7.2f}')
        plot_errors(out / 'live_attitude_error.png',
                    f'{Path(args.bag).name}: live, against its ground truth', t, valid, errors)
        print(f'plot: {out / "live_attitude_error.png"}')
    finally:
        if node_proc is not None:
            node_proc.send_signal(signal.SIGINT)
            try:
                node_proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                node_proc.kill()
        executor.shutdown()
        if player is not None:
            player.destroy_node()
        monitor.destroy_node()
        shutdown_rclpy()
    return 0


if __name__ == '__main__':
    sys.exit(main())
