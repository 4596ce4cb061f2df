# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""denoise-imu play: a bag's IMU published in real time."""

from helpers import DOMAIN, SAMPLE, sample_messages
import pytest


def test_player_publishes_a_bag_in_order_with_clock(harness):
    from denoise_imu_ros.runtime.player import Player, read_imu_messages
    from rosgraph_msgs.msg import Clock
    messages = read_imu_messages(SAMPLE)[:300]
    assert messages == sample_messages(300)  # what the other tests play
    h = harness()
    clocks = []
    h.client.create_subscription(Clock, '/clock', clocks.append, 1000)
    player = Player(messages, rate=20.0, clock=True, context=h.ctx)
    h.executor.add_node(player)
    for k, _ in enumerate(player.play()):  # one executor: let the node keep pace
        h.spin_until(lambda: h.processed() > k)
    h.spin_until(lambda: len(h.corrected) == 300 and len(clocks) == 300)
    assert [m.header.stamp for m in h.corrected] == [m.header.stamp for m in messages]
    assert [c.clock for c in clocks] == [m.header.stamp for m in messages]
    assert h.node._denoiser.counts['accepted'] == 300


def test_a_stamp_jump_is_no_reason_to_wait_for_it(harness, monkeypatch):
    """A zero stamp first, an hour's jump ahead, a jump back: played at the pace around."""
    from denoise_imu_ros.runtime import player as player_module
    from denoise_imu_ros.runtime.player import Player
    from helpers import imu_msg
    waits = []
    monkeypatch.setattr(player_module.time, 'sleep', waits.append)
    monkeypatch.setattr(player_module.time, 'monotonic', lambda: sum(waits))  # waits only
    stamps = [0, 10 ** 9, 10 ** 9 + 3600 * 10 ** 9, 2 * 10 ** 9, 2 * 10 ** 9 + 5_000_000]
    messages = [imu_msg(t, [0.0, 0.0, 0.0], [0.0, 0.0, 9.81]) for t in stamps]
    player = Player(messages, context=harness().ctx)
    assert len(list(player.play())) == 5
    assert sum(waits) == pytest.approx(1.0 + 1.0 + 0.0 + 0.005)  # each wait at most 1 s
    assert max(waits) <= player_module.SLEEP_SLICE_S + 1e-12  # a signal is seen at once
    player.destroy_node()


def test_play_command_feeds_the_node(harness, monkeypatch, tmp_path, capsys, euroc):
    import threading
    from denoise_imu_ros.cli import main as cli
    monkeypatch.setenv('ROS_DOMAIN_ID', str(DOMAIN))
    # a reliable input deep enough for the whole bag: on a loaded machine a best-effort
    # one may lose what play sent (as CI once did), and the node is not under test here
    h = harness(input_queue_depth=1000,
                **{'qos_overrides./imu/data_raw.subscription.reliability': 'reliable'})
    bag = tmp_path / 'short'
    assert cli(['convert', '--input', str(euroc / 'V1_01_easy'), '--out', str(bag),
                '--duration', '2']) == 0
    result = []
    thread = threading.Thread(target=lambda: result.append(cli(['play', '--input', str(bag),
                                                                '--rate', '2'])))
    thread.start()
    while thread.is_alive():
        h.executor.spin_once(timeout_sec=0.01)
    assert result == [0]
    h.spin_until(lambda: len(h.corrected) == 400)
    assert 'published 400 IMU messages' in capsys.readouterr().out


@pytest.mark.parametrize('signame', ['SIGTERM', 'SIGINT'])
def test_sigterm_stops_play_quietly_and_ctrl_c_is_an_interruption(signame):
    """A supervisor's SIGTERM (or a timeout) shut rclpy down: no traceback, exit 0."""
    import os
    import select
    import signal
    import subprocess
    import sys
    import time
    env = {**os.environ, 'ROS_DOMAIN_ID': str(DOMAIN)}
    play = subprocess.Popen([sys.executable, '-m', 'denoise_imu_ros.cli', 'play', '--input',
                             str(SAMPLE), '--wait', '0'], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    # the signal must come once play is publishing (rclpy's handlers in place), however
    # long the imports take on a loaded machine: its "playing anyway" warning says so
    err, deadline = b'', time.monotonic() + 60
    while b'playing anyway' not in err and time.monotonic() < deadline:
        if select.select([play.stderr], [], [], 1.0)[0]:
            chunk = os.read(play.stderr.fileno(), 4096)
            if not chunk:
                break
            err += chunk
    assert b'playing anyway' in err, err
    time.sleep(0.2)  # a fifth of a second of the 90 s bag: mid-play
    play.send_signal(getattr(signal, signame))
    out, rest = play.communicate(timeout=30)
    out, err = out.decode(), (err + rest).decode()
    assert 'Traceback' not in err, err
    if signame == 'SIGTERM':
        assert play.returncode == 0 and '(stopped: ' in out and ' of 18000)' in out, out
    else:  # Ctrl-C: as every command, one line and 130
        assert play.returncode == 130 and out == '', out
        assert err.rstrip().endswith('denoise-imu play: interrupted'), err
