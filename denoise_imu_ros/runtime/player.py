# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
``denoise-imu play``: publish a bag's IMU messages in real time (``ros2 bag play`` stand-in).

Messages go out at their recorded pace (scaled by ``rate``), stamped as recorded; with
``clock`` a ``/clock`` message carrying each IMU stamp precedes it, for ``use_sim_time``.
The pace follows the stamp intervals, each at most MAX_PAUSE_S (a stamp jump forward, a
zero stamp, is no reason to wait for years) and none negative (after a jump back the
messages keep their pace); such jumps are counted and said.
"""

from __future__ import annotations

import math
from pathlib import Path
import signal
import threading
import time
from typing import Any, Iterator

from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.validate_topic_name import InvalidTopicNameException, validate_topic_name
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu

from ..core import msgs
from ..core.errors import DatasetError, DenoiseError, OptionError
from ..core.msgs import stamp_ns
from ..data.bags import CORRUPT, IMU_TYPE, open_bag, pick_connections

RCLPY_TYPES = msgs.rclpy_types()
MAX_PAUSE_S = 1.0  # the longest wait between two messages, in recorded seconds
SLEEP_SLICE_S = 0.1  # a signal's shutdown is seen within this


def read_imu_messages(path: str | Path, imu_topic: str | None = None) -> list[Imu]:
    """All IMU messages of a ROS 1 or ROS 2 bag, as rclpy messages, in bag order."""
    path = Path(path)
    try:
        with open_bag(path) as reader:
            conns = pick_connections(reader, imu_topic, (IMU_TYPE,), 'IMU', path)
            return [msgs.copy_imu(RCLPY_TYPES, reader.deserialize(raw, c.msgtype))
                    for c, _, raw in reader.messages(connections=conns)]
    except CORRUPT as err:
        raise DatasetError(f'{path}: cannot read bag: {" ".join(str(err).split())}') from err


class Player(Node):
    """Publishes a list of Imu messages at their recorded pace."""

    def __init__(self, messages: list[Imu], topic: str = 'imu/data_raw', rate: float = 1.0,
                 clock: bool = False, **kwargs: Any) -> None:
        super().__init__('imu_player', **kwargs)
        if not (math.isfinite(rate) and rate > 0):
            raise OptionError(f'--rate {rate:g}: playback rate must be a positive number')
        self._messages, self._rate = messages, rate
        # Reliable: reaches best-effort and reliable subscribers alike.
        self._pub = self.create_publisher(Imu, topic, QoSProfile(
            depth=1000, reliability=ReliabilityPolicy.RELIABLE))
        self._clock = self.create_publisher(Clock, '/clock', 10) if clock else None

    def has_subscribers(self) -> bool:
        """Whether a subscriber of the IMU topic has matched this publisher."""
        return self._pub.get_subscription_count() > 0

    def wait_for_subscribers(self, timeout_s: float = 10.0) -> bool:
        """Give discovery a moment; True when the IMU topic has a subscriber."""
        deadline = time.monotonic() + timeout_s
        while not self.has_subscribers() and time.monotonic() < deadline:
            time.sleep(0.05)
        return self.has_subscribers()

    def play(self) -> Iterator[Imu]:
        """Publish every message on schedule, yielding each one after it went out."""
        due, last, jumps = time.monotonic(), None, 0
        for msg in self._messages:
            stamp = stamp_ns(msg.header)
            if last is not None:
                step = (stamp - last) * 1e-9
                jumps += not 0.0 <= step <= MAX_PAUSE_S
                due += min(max(step, 0.0), MAX_PAUSE_S) / self._rate
            last = stamp
            if not self._sleep_until(due):  # SIGTERM or SIGINT shut rclpy down: stop
                return
            try:
                if self._clock is not None:
                    self._clock.publish(Clock(clock=msg.header.stamp))
                self._pub.publish(msg)
            except Exception:  # rclpy's RCLError, when a signal came since the check
                if self.context.ok():
                    raise
                return
            yield msg
        if jumps:
            self.get_logger().warning(f'{jumps} stamp jumps (backwards, or more than '
                                      f'{MAX_PAUSE_S:g} s ahead) played without their wait')

    def _sleep_until(self, due: float) -> bool:
        """Wait until ``due`` (time.monotonic) in slices; False once rclpy is shut down."""
        while (left := due - time.monotonic()) > 0:
            if not self.context.ok():
                return False
            time.sleep(min(left, SLEEP_SLICE_S))
        return self.context.ok()


def main(bag: str, imu_topic: str | None, topic: str, rate: float, clock: bool,
         wait_s: float = 10.0) -> int:
    """Run ``denoise-imu play``: initialise rclpy, publish the bag, shut down."""
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from .node import shutdown_rclpy
    try:
        validate_topic_name(topic)
    except InvalidTopicNameException as err:
        raise DenoiseError(f'--topic {topic!r}: {" ".join(str(err).split()[:12])}') from err
    messages = read_imu_messages(bag, imu_topic)
    # rclpy's own handler shuts rclpy down and then calls the one before it, this: Ctrl-C
    # is known even where its KeyboardInterrupt is lost in a publish that the shutdown ended
    interrupts: list[int] = []

    def on_sigint(signum: int, _frame: object) -> None:
        interrupts.append(signum)
        raise KeyboardInterrupt

    main_thread = threading.current_thread() is threading.main_thread()
    before = signal.signal(signal.SIGINT, on_sigint) if main_thread else None
    rclpy.init()
    player, count, interrupted, where = None, 0, False, topic
    try:
        player = Player(messages, topic=topic, rate=rate, clock=clock)
        where = player.resolve_topic_name(topic)
        # Discovery can miss its first announcements on a loaded machine, and the next
        # ones come ~3 s later: 2 s of waiting lost 80 % of a test bag under load.
        if not player.wait_for_subscribers(timeout_s=wait_s):
            player.get_logger().warning(f'no subscriber on {where} after {wait_s:g} s; '
                                        'playing anyway')
        for _ in player.play():
            count += 1
    except KeyboardInterrupt:  # Ctrl-C: after the clean-up, the command's one line and 130
        interrupted = True
    except ExternalShutdownException:
        pass
    finally:
        if player is not None:
            player.destroy_node()
        shutdown_rclpy()
        if main_thread:
            signal.signal(signal.SIGINT, before)
    if interrupted or interrupts:
        raise KeyboardInterrupt
    stopped = '' if count == len(messages) else f' (stopped: {count} of {len(messages)})'
    print(f'published {count} IMU messages from {bag} on {where}{stopped}')
    return 0
