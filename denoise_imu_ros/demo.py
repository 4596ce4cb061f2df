# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Live demo: the node, a bag player and a monitor, over DDS on this machine.

``make demo`` runs ``gyro_denoiser`` (shipped EuRoC model) as its own process, plays the
bundled EuRoC test-sequence sample into ``imu/data_raw`` in real time, and monitors
``imu/attitude`` and ``imu/data`` against the ground truth stored in the same bag. As
the recording plays it prints the error of each beside what a user would otherwise run
(computed here from the same samples): the raw gyro and the calibrated IMU integrated
(open loop, against ``imu/attitude``), and VQF fed the calibrated IMU with the
calibration's stored filter settings (gravity-aided, against ``imu/data``, the
orientation a robot should use); then it plots both groups. Open-loop trajectories start
from the ground truth at the node's first output (the node's own start is
gravity-aligned with yaw 0, a constant world rotation the monitor removes); a
gravity-aided orientation keeps its tilt and has its yaw aligned once, 1.5 s in: the
conventions of ``denoise-imu eval``.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field
import math
import os
from pathlib import Path
import signal
import subprocess
import sys
import threading
import time
from typing import Callable

from geometry_msgs.msg import QuaternionStamped
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import Imu

from .core.errors import DatasetError, DenoiseError, OptionError
from .core.metrics import ALIGN_AT_S, align_yaw, error_components, integrate
from .core.modelfile import read_model_file, sample_rate, shipped_models
from .core.msgs import stamp_ns
from .core.records import Sequence
from .data.load import load_sequence
from .evaluation.plots import plot_errors
from .pipeline.fusion import fuse, step_periods
from .pipeline.streaming import StreamingCorrector
from .runtime.node import shutdown_rclpy
from .runtime.player import Player, read_imu_messages

SAMPLE = Path(__file__).parent / 'sample' / 'euroc_V1_03_90s'
OPEN_LOOP, FUSED = 'imu/attitude', 'imu/data'
RELIABLE = QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE)


@dataclass(frozen=True)
class Baselines:
    """What a user would otherwise run on the same samples, computed here."""

    raw: np.ndarray                        # the raw gyro (N, 3)
    calibrated: np.ndarray | None = None   # the calibrated IMU's gyro (N, 3), if shipped
    calibrated_vqf: np.ndarray | None = None  # VQF fed the calibrated IMU: xyzw (N, 4)


def _baselines(model: str, seq: Sequence) -> Baselines:
    """
    Return the baselines of ``<dataset>_calibrated``, the model's calibrated IMU.

    Run from the bag's first IMU sample, as the node is, and kept where it has poses.
    """
    name = f'{read_model_file(model).meta.dataset}_calibrated'
    if name not in shipped_models():
        return Baselines(seq.imu[:, :3])
    calib = read_model_file(name)
    gyro = StreamingCorrector(calib.config, calib.arrays).process(seq.stream)
    rate = sample_rate(calib)
    fused = fuse(gyro, seq.stream[:, 3:], rate, calib.meta.fusion.chosen,
                 step_periods(seq.stream_stamp_ns, rate), seq.stream[:, :3])
    return Baselines(seq.imu[:, :3], seq.on_poses(gyro), seq.on_poses(fused))


@dataclass
class Received:
    """The node's outputs as the monitor got them: (stamp ns, xyzw) per topic."""

    topics: dict[str, list[tuple[int, tuple[float, ...]]]] = field(
        default_factory=lambda: {OPEN_LOOP: [], FUSED: []})

    def attitude(self, msg: QuaternionStamped) -> None:
        """Keep an ``imu/attitude`` message."""
        q = msg.quaternion
        self.topics[OPEN_LOOP].append((stamp_ns(msg.header), (q.x, q.y, q.z, q.w)))

    def fused(self, msg: Imu) -> None:
        """Keep an ``imu/data`` message's orientation."""
        q = msg.orientation
        self.topics[FUSED].append((stamp_ns(msg.header), (q.x, q.y, q.z, q.w)))


def _errors(seq: Sequence, received: list[tuple[int, tuple[float, ...]]], topic: str,
            base: Baselines) -> tuple[np.ndarray, np.ndarray, dict[str, tuple]]:
    """
    Time, the stamps scored and (angle, tilt, yaw) errors per method at the node's stamps.

    ``imu/attitude`` beside the raw and calibrated gyro integrated from the ground truth
    at the node's first output; ``imu/data`` beside VQF on the calibrated IMU, each with
    its yaw aligned once, ALIGN_AT_S in, and scored from there.
    """
    stamps, quats = map(np.array, zip(*received))
    idx = np.searchsorted(seq.stamp_ns, stamps)
    keep = (idx < len(seq)) & (seq.stamp_ns[np.minimum(idx, len(seq) - 1)] == stamps)
    idx, node = idx[keep], Rotation.from_quat(quats[keep])
    if not len(idx):
        raise DatasetError(f'{seq.name}: none of the {topic} orientations received has a '
                           'stamp of its IMU samples')
    gt, first = Rotation.from_quat(seq.gt_quat[idx]), idx[0]
    t = (seq.stamp_ns[idx] - seq.stamp_ns[first]) * 1e-9
    if topic == OPEN_LOOP:
        gyros = {'raw gyro': base.raw, 'calibrated IMU': base.calibrated}
        est = {label: integrate(seq.gt_quat[first], g[first:-1], seq.dt[first:])[idx - first]
               for label, g in gyros.items() if g is not None}
        est[f'gyro_denoiser {topic}'] = (gt[0] * node[0].inv()) * node  # the same start
        return t, seq.gt_valid[idx], {k: error_components(r, gt) for k, r in est.items()}
    est = {} if base.calibrated_vqf is None else {
        'calibrated IMU + VQF': Rotation.from_quat(base.calibrated_vqf[idx])}
    est[f'gyro_denoiser {topic}'] = node
    k = int(np.searchsorted(t, min(ALIGN_AT_S, t[-1])))
    return t, seq.gt_valid[idx] & (t >= t[k]), {
        label: error_components(align_yaw(r, gt, k), gt) for label, r in est.items()}


def main(argv: list[str] | None = None) -> int:
    """Run the live demo; returns the node's exit status, 1 on an error, or 0."""
    try:
        return _demo(argv)
    except DenoiseError as err:
        print(f'denoise-imu-demo: error: {err}', file=sys.stderr)
        return 1


def _options(argv: list[str] | None) -> argparse.Namespace:
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
    return args


def _demo(argv: list[str] | None) -> int:
    args = _options(argv)
    seq = load_sequence(args.bag)
    base = _baselines(args.model, seq)
    messages = read_imu_messages(args.bag)
    if args.seconds is not None:
        t0 = stamp_ns(messages[0].header)
        messages = [m for m in messages
                    if (stamp_ns(m.header) - t0) * 1e-9 < args.seconds]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rclpy.init()
    try:
        received = Received()
        status = _live(args, messages, received, lambda: _progress(seq, received, base))
        if status:
            return status
        _summary(out, Path(args.bag).name, seq, received, base, len(messages))
    finally:
        shutdown_rclpy()
    return 0


def _progress(seq: Sequence, received: Received, base: Baselines) -> str:
    """One line of the latest error of every method (deg), open loop then gravity-aided."""
    columns = []
    for topic in (OPEN_LOOP, FUSED):
        if len(received.topics[topic]) > 1:
            columns += [e[0][-1] for e in _errors(seq, received.topics[topic], topic,
                                                  base)[2].values()]
    return '  '.join(f'{c:9.2f}' for c in columns)


def _live(args: argparse.Namespace, messages: list, received: Received,
          progress: Callable[[], str]) -> int:
    """Run the node and the player; collect its outputs; return non-zero if it failed."""
    monitor = rclpy.create_node('attitude_monitor')
    monitor.create_subscription(QuaternionStamped, OPEN_LOOP, received.attitude, RELIABLE)
    monitor.create_subscription(Imu, FUSED, received.fused, RELIABLE)
    executor = SingleThreadedExecutor()
    executor.add_node(monitor)
    player = node_proc = None
    try:
        player = Player(messages, rate=args.rate)
        node_proc = subprocess.Popen(
            [sys.executable, '-m', 'denoise_imu_ros.runtime.node', '--ros-args', '-p',
             f'model:={args.model}', '-p', 'fixed_frame:=world',
             # every sample scored against the ground truth: none dropped on a busy machine
             '-p', 'qos_overrides./imu/data_raw.subscription.reliability:=reliable',
             '--log-level', 'warn'],
            env=dict(os.environ))
        print(f'waiting for gyro_denoiser (model {args.model}) ...', flush=True)
        while not player.has_subscribers() or not all(
                monitor.count_publishers(topic) for topic in (OPEN_LOOP, FUSED)):
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
              f'at {args.rate:g}x; error against the ground truth (deg):')
        print(f'{"time":>7s}  {"raw gyro":>9s}  {"calibrated":>10s}  {"attitude":>9s}  '
              f'{"calib+VQF":>9s}  {"imu/data":>9s}', flush=True)
        _collect(executor, received, node_proc, done, len(messages), progress)
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
    return 0


def _collect(executor: SingleThreadedExecutor, received: Received,
             node_proc: subprocess.Popen, done: threading.Event, expected: int,
             progress: Callable[[], str]) -> None:
    """
    Spin until the player is done and the node quiet; print a line every 10 s.

    Quiet is 2 s without a new attitude: a node that lags behind a loaded machine is
    waited for while it still publishes.
    """
    attitudes = received.topics[OPEN_LOOP]
    next_report, quiet_since, seen = 10.0, None, 0
    while True:
        executor.spin_once(timeout_sec=0.05)
        if len(attitudes) > 1 and (attitudes[-1][0] - attitudes[0][0]) * 1e-9 >= next_report:
            print(f'{next_report:6.1f}s  {progress()}', flush=True)
            next_report += 10.0
        if node_proc.poll() is not None:
            raise DenoiseError(f'gyro_denoiser stopped (exit {node_proc.returncode}) '
                               f'after {len(attitudes)} attitudes')
        if done.is_set():
            if quiet_since is None or len(attitudes) > seen:
                quiet_since, seen = time.monotonic(), len(attitudes)
            if len(attitudes) >= expected or time.monotonic() - quiet_since > 2.0:
                return


def _summary(out: Path, name: str, seq: Sequence, received: Received, base: Baselines,
             played: int) -> None:
    """Print each method's RMS and final error and plot them, open loop and gravity-aided."""
    if not received.topics[OPEN_LOOP]:
        raise DenoiseError('no attitude received from gyro_denoiser')
    print(f'\n{len(received.topics[OPEN_LOOP])}/{played} samples corrected live over DDS; '
          'error against the ground truth (RMS / final, deg):')
    plots = {OPEN_LOOP: ('live_attitude_error.png', 'open loop (imu/attitude), from the '
                         'ground truth at the first output'),
             FUSED: ('live_fused_error.png', f'gravity-aided (imu/data), yaw aligned '
                     f'{ALIGN_AT_S:g} s in')}
    for topic, (png, title) in plots.items():
        if not received.topics[topic]:
            print(f' {topic}: nothing received')
            continue
        t, scored, errors = _errors(seq, received.topics[topic], topic, base)
        print(f' {title}, over {t[-1]:.0f} s:')
        for label, (angle, _, _) in errors.items():
            rms = float(np.sqrt(np.mean(angle[scored] ** 2)))
            print(f'  {label:27s}: {rms:7.2f} / {angle[-1]:7.2f}')
        plot_errors(out / png, f'{name}: live {title}', t, scored, errors)
        print(f' plot: {out / png}')


if __name__ == '__main__':
    sys.exit(main())
