# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
ROS 1 / ROS 2 bags through ``rosbags``: read a recording, write one.

Reading takes an IMU topic (``sensor_msgs/Imu``) and a pose topic
(``geometry_msgs/PoseStamped``, ``geometry_msgs/TransformStamped`` or
``nav_msgs/Odometry``); either is auto-detected when it is the only topic of its kind.
Message header stamps are used, not the bag's receive times.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
import struct
import tempfile
from typing import Any, NamedTuple
import warnings

import numpy as np
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer, WriterError
from rosbags.typesys import get_typestore, Stores

from .trajectory import drop_rows, dropped_text, not_poses, out_of_order
from ..core import msgs
from ..core.atomic import atomic_output
from ..core.errors import DatasetError, DataWarning
from ..core.memo import files_key, Kept
from ..core.msgs import stamp_ns
from ..core.records import check_recording, Recording

IMU_TYPE = 'sensor_msgs/msg/Imu'
POSE_TYPES = ('geometry_msgs/msg/PoseStamped', 'geometry_msgs/msg/TransformStamped',
              'nav_msgs/msg/Odometry', 'geometry_msgs/msg/PoseWithCovarianceStamped')
# taken unnamed only where the bag holds no other pose type: RViz's /initialpose and a
# localiser's pose (AMCL's) are of this type beside the pose source
NAMED_POSE_TYPES = ('geometry_msgs/msg/PoseWithCovarianceStamped',)
TF_TYPE = 'tf2_msgs/msg/TFMessage'
# a bag's quaternions off unit by more are no pose (check_recording's band: a float32
# publisher's, or one that never normalises, are further off than a text file's digits)
BAG_UNIT_TOLERANCE = 0.5
# Topic names `denoise-imu convert` writes (EuRoC's bags also call the IMU /imu0).
IMU_TOPIC = '/imu0'
POSE_TOPIC = '/groundtruth/pose'

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
BAG_TYPES = msgs.bag_types(TYPESTORE)
# IMU samples and poses of the last bags read, kept (core.memo; 56 bytes each): reading
# a bag's messages costs far more than keeping their arrays
MESSAGES_KEPT = 4_000_000


class _Messages(NamedTuple):
    """A bag's IMU and pose topics read, and their stamps and values in bag order."""

    imu_topic: str
    pose_topic: str
    imu_stamp_ns: np.ndarray  # (N,) int64
    imu: np.ndarray           # (N, 6) gyro, accelerometer
    gt_stamp_ns: np.ndarray   # (M,) int64
    gt: np.ndarray            # (M, 7) xyzw, position


_READ: Kept[_Messages] = Kept(MESSAGES_KEPT, lambda m: len(m.imu) + len(m.gt))


def _pose(msg: Any, msgtype: str) -> tuple[Any, Any]:
    """(position, orientation) of any supported pose message."""
    if msgtype == 'geometry_msgs/msg/TransformStamped':
        return msg.transform.translation, msg.transform.rotation
    if msgtype in ('nav_msgs/msg/Odometry', 'geometry_msgs/msg/PoseWithCovarianceStamped'):
        return msg.pose.pose.position, msg.pose.pose.orientation
    return msg.pose.position, msg.pose.orientation


def pick_connections(reader: AnyReader, topic: str | None, types: tuple[str, ...],
                     what: str, path: Path, named: tuple[str, ...] = ()) -> Any:
    """
    Return the connections of ``topic``, checked against ``types``, or the only candidate.

    A topic of a ``named`` type is a candidate only where none of another type is.
    """
    conns = reader.connections
    listing = ', '.join(sorted({f'{c.topic} [{c.msgtype}]' for c in conns})) or 'none'
    if topic is None:
        cands = ({c.topic for c in conns if c.msgtype in types and c.msgtype not in named}
                 or {c.topic for c in conns if c.msgtype in named})
        if not cands:  # nothing to name: the bag lacks what the command needs
            tf = any(c.msgtype == TF_TYPE for c in conns) and what == 'pose'
            raise DatasetError(f'{path}: no {what} topic ({" or ".join(types)}) in this bag'
                               + (': this command needs ground-truth poses' if what == 'pose'
                                  else '') + f' (topics: {listing})'
                               + ("; /tf is not read: record the pose source's own topic, or "
                                  'give its poses as trajectory files (--poses)' if tf else ''))
        if len(cands) > 1:
            raise DatasetError(f'{path}: {len(cands)} candidate {what} topics, pass one with '
                               f'--{what.lower()}-topic ({what.lower()}_topic in a recipe) '
                               f'(topics: {listing})')
        topic = cands.pop()
    norm = '/' + topic.lstrip('/')  # 'imu0' and '/imu0' name the same topic
    chosen = [c for c in conns if '/' + c.topic.lstrip('/') == norm]
    if not chosen:
        raise DatasetError(f'{path}: no topic {topic!r} (topics: {listing})')
    if chosen[0].msgtype not in types:
        raise DatasetError(f'{path}: topic {topic!r} has type {chosen[0].msgtype}, '
                           f'expected {" or ".join(types)}')
    return chosen


# What rosbags' parsers raise on a file that is not a bag (a garbage .bag gives
# UnicodeDecodeError in the ROS 1 reader, for one).
CORRUPT = (AnyReaderError, UnicodeDecodeError, ValueError, EOFError, IndexError, KeyError,
           struct.error)


@contextmanager
def open_bag(path: str | Path) -> Iterator[AnyReader]:
    """Open a ROS 1 or ROS 2 bag for reading; a missing or corrupt one is a DatasetError."""
    path = Path(path)
    if not path.exists():
        raise DatasetError(f'{path}: bag not found')
    with tempfile.TemporaryDirectory() as tmp:
        if path.is_dir() and path.suffix == '.bag':  # rosbags reads *.bag as ROS 1 files
            Path(tmp, 'bag').symlink_to(path.resolve(), target_is_directory=True)
            source = Path(tmp, 'bag')
        else:
            source = path
        reader = AnyReader([source], default_typestore=TYPESTORE)
        try:
            reader.open()
        except CORRUPT as err:
            raise DatasetError(f'{path}: not a readable bag ({type(err).__name__}: '
                               f'{" ".join(str(err).split())[:120]})') from err
        try:
            yield reader
        finally:
            reader.close()


def is_compressed(reader: AnyReader) -> bool:
    """
    Whether a bag's messages are compressed, per message, per file or inside MCAP chunks.

    ``ros2 bag record --storage-preset-profile zstd_fast`` and rosbags' storage mode
    compress the MCAP chunks and leave ``compression_mode`` empty in ``metadata.yaml``;
    only the chunk records say it (rosbags' MCAP reader keeps them).
    """
    for bag in reader.readers:
        if getattr(bag, 'compression_mode', None):
            return True
        for storage in getattr(getattr(bag, 'storage', None), 'storages', ()):
            if any(chunk.compression for chunk in getattr(storage, 'chunks', ())):
                return True
    return False


def messages_as_written(reader: AnyReader) -> Iterator[tuple[Any, int, bytes]]:
    """
    Yield a bag's messages (connection, receive time, raw) in the order they were written.

    That is what a live subscriber saw, where the receive times may not say it: a host
    clock stepped back while recording (NTP, chrony) steps them as well, and rosbags'
    reader, which sorts by them, would interleave the stretches before and after. A ROS 2
    bag keeps its write order (SQLite rows, MCAP records, split files in turn); a ROS 1
    bag (converted first) and a storage rosbags does not expose come in receive order.
    """
    storages = [storage for bag in reader.readers
                for storage in getattr(getattr(bag, 'storage', None), 'storages', ())]
    if not storages or not all(hasattr(s, 'dbconn') or hasattr(s, 'messages_scan')
                               for s in storages):
        yield from reader.messages()
        return
    known = {(c.topic, c.msgtype): c for c in reader.connections}
    for storage in storages:
        local = {c.id: known[c.topic, c.msgtype] for c in storage.connections}
        if hasattr(storage, 'dbconn'):
            rows = storage.dbconn.execute(
                'SELECT topic_id, timestamp, data FROM messages ORDER BY id')
            for cid, stamp, raw in rows:
                yield local[cid], stamp, raw
        else:
            for conn, stamp, raw in storage.messages_scan(storage.connections):
                yield local[conn.id], stamp, raw


def _messages(path: Path, imu_topic: str | None, pose_topic: str | None,
              with_pose: bool) -> _Messages:
    """Read a bag's IMU and pose messages."""
    try:
        with open_bag(path) as reader:
            imu_conns = pick_connections(reader, imu_topic, (IMU_TYPE,), 'IMU', path)
            pose_conns = (pick_connections(reader, pose_topic, POSE_TYPES, 'pose', path,
                                           NAMED_POSE_TYPES) if with_pose else [])
            imu_t, imu, gt_t, gt = [], [], [], []
            for conn, _, raw in reader.messages(connections=imu_conns + pose_conns):
                msg = reader.deserialize(raw, conn.msgtype)
                if conn.msgtype == IMU_TYPE:
                    w, a = msg.angular_velocity, msg.linear_acceleration
                    imu_t.append(stamp_ns(msg.header))
                    imu.append((w.x, w.y, w.z, a.x, a.y, a.z))
                else:
                    p, q = _pose(msg, conn.msgtype)
                    gt_t.append(stamp_ns(msg.header))
                    gt.append((q.x, q.y, q.z, q.w, p.x, p.y, p.z))
    except CORRUPT as err:
        raise DatasetError(f'{path}: cannot read bag: {" ".join(str(err).split())}') from err
    return _Messages(imu_conns[0].topic, pose_conns[0].topic if pose_conns else '',
                     np.array(imu_t, dtype=np.int64),
                     np.array(imu, dtype=np.float64).reshape(-1, 6),
                     np.array(gt_t, dtype=np.int64),
                     np.array(gt, dtype=np.float64).reshape(-1, 7))


def read_bag(path: str | Path, imu_topic: str | None = None,
             pose_topic: str | None = None, with_pose: bool = True) -> Recording:
    """
    Read IMU and ground-truth pose from a ROS 1 or ROS 2 (sqlite3/mcap) bag.

    With ``with_pose=False`` only the IMU is read (the ground-truth arrays are empty).
    Samples are taken in header-stamp order: a recorder's transport latency reorders
    the receive order by a few milliseconds, and the stamps, not the arrival, are the
    measurement times (process-bag runs its pipeline in the same order). Poses that are
    not poses (non-finite, a quaternion off unit by more than BAG_UNIT_TOLERANCE) or that
    repeat a stamp, as a VIO's odometry can hold, are dropped and counted as in a
    trajectory file (:mod:`.trajectory`); taken in stamp order, none steps back.
    """
    path = Path(path)
    files = files_key(path)
    read = _READ.get(None if files is None else (files, imu_topic, pose_topic, with_pose),
                     lambda: _messages(path, imu_topic, pose_topic, with_pose))
    gt_order = np.argsort(read.gt_stamp_ns, kind='stable')  # copies: the kept arrays stay
    gt_stamps, gt_arr = read.gt_stamp_ns[gt_order], read.gt[gt_order]
    dropped: dict[str, int] = {}
    gt_stamps, gt_arr = drop_rows(not_poses(gt_arr, gt_arr[:, :4], gt_arr[:, 4:],
                                            BAG_UNIT_TOLERANCE), dropped, gt_stamps, gt_arr)
    gt_stamps, gt_arr = drop_rows(out_of_order(gt_stamps), dropped, gt_stamps, gt_arr)
    if dropped:
        unset = dropped.get('duplicate stamps', 0) > len(gt_stamps)  # most share one stamp
        warnings.warn(f'{path}: {read.pose_topic}: {len(gt_stamps)} poses kept; '
                      f'{dropped_text(dropped)}' + (' (header stamps not set?)' if unset else ''),
                      DataWarning, stacklevel=2)
    if with_pose and (not len(read.imu) or len(gt_stamps) < 2):
        raise DatasetError(f'{path}: {len(read.imu)} IMU messages and {len(gt_stamps)} '
                           f'{"usable " if dropped else ""}poses: need IMU messages and two '
                           'poses at least')
    if not len(read.imu):
        raise DatasetError(f'{path}: no IMU messages on {read.imu_topic}')
    imu_order = np.argsort(read.imu_stamp_ns, kind='stable')
    name = path.stem if path.is_file() else path.name
    rec = Recording(name=name, source=str(path), imu_stamp_ns=read.imu_stamp_ns[imu_order],
                    imu=read.imu[imu_order], gt_stamp_ns=gt_stamps, gt_quat=gt_arr[:, :4],
                    gt_pos=gt_arr[:, 4:])
    check_recording(rec)
    return rec


def imu_message(stamp: int, gyro: np.ndarray, accel: np.ndarray,
                frame_id: str = 'imu0') -> Any:
    """Build a rosbags ``sensor_msgs/Imu`` with no orientation (covariance[0] = -1)."""
    return msgs.imu(BAG_TYPES, msgs.header(BAG_TYPES, stamp, frame_id), gyro, accel)


def write_bag(rec: Recording, out: str | Path, storage: str = 'mcap',
              compress: bool = False, imu_topic: str = IMU_TOPIC,
              pose_topic: str = POSE_TOPIC) -> None:
    """
    Write a recording as a ROS 2 bag: IMU (``sensor_msgs/Imu``) and pose (``PoseStamped``).

    The default topic names are EuRoC's; a robot's (``/imu/data_raw``, ``/mocap/pose``)
    make bags like the ones users record. ``compress`` uses zstd (inside the MCAP
    chunks, or per message for sqlite3).
    """
    plugin = {'mcap': StoragePlugin.MCAP, 'sqlite3': StoragePlugin.SQLITE3}.get(storage)
    if plugin is None:
        raise DatasetError(f'unknown bag storage {storage!r} (mcap or sqlite3)')
    with atomic_output(out) as tmp:
        _write_bag(rec, tmp, plugin, compress, imu_topic, pose_topic)


def _write_bag(rec: Recording, out: Path, plugin: StoragePlugin, compress: bool,
               imu_topic: str, pose_topic: str) -> None:
    t = TYPESTORE.types
    try:
        writer = Writer(out, version=9, storage_plugin=plugin)
        if compress:
            writer.set_compression(
                CompressionMode.STORAGE if plugin == StoragePlugin.MCAP
                else CompressionMode.MESSAGE, CompressionFormat.ZSTD)
        with writer:
            imu_conn = writer.add_connection(imu_topic, IMU_TYPE, typestore=TYPESTORE)
            pose_conn = writer.add_connection(pose_topic, POSE_TYPES[0], typestore=TYPESTORE)
            for stamp, row in zip(rec.imu_stamp_ns, rec.imu):
                msg = imu_message(stamp, row[:3], row[3:])
                writer.write(imu_conn, int(stamp), TYPESTORE.serialize_cdr(msg, IMU_TYPE))
            for stamp, q, p in zip(rec.gt_stamp_ns, rec.gt_quat, rec.gt_pos):
                msg = t[POSE_TYPES[0]](header=msgs.header(BAG_TYPES, stamp, 'world'), pose=t[
                    'geometry_msgs/msg/Pose'](
                    position=t['geometry_msgs/msg/Point'](x=p[0], y=p[1], z=p[2]),
                    orientation=t['geometry_msgs/msg/Quaternion'](
                        x=q[0], y=q[1], z=q[2], w=q[3])))
                writer.write(pose_conn, int(stamp), TYPESTORE.serialize_cdr(msg, POSE_TYPES[0]))
    except (WriterError, FileExistsError) as err:
        raise DatasetError(f'{out.name}: cannot write bag: {err}') from err
