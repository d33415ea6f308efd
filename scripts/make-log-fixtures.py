#!/usr/bin/env python3
"""Writes the binary log fixtures of recording/tests/fixtures/logs/ from a simulated hand-held session,
each with its format's reference tool, and checks that the tool reads its file back.

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install pyulog==1.3.0 pymavlink==2.4.50 \
        mcap==1.6.0 mcap-ros2-support==0.6.0 numpy==2.4.6
    cargo run -p host -- simulate-hand --out /tmp/hand.csv --rate-hz 100 --gyro-unit rad/s --seed 1
    /tmp/venv/bin/python scripts/make-log-fixtures.py /tmp/hand.csv recording/tests/fixtures/logs

The session is cut to its first ROWS rows (60 s, ten still positions and the turns between them) to
keep the files small. Each format gets the accelerometer in m/s², the gyro in rad/s and a slow
temperature ramp (24.0 to 24.6 °C) where the format has one:

- hand.ulg: PX4 ULog written by pyulog's own writer (ULog.write_ulog) from a ULog whose
  sensor_accel and sensor_gyro data were replaced by the session's (PX4's message definitions of
  those topics, multi_id 0), with one 20 ms dropout (two samples lost) at row DROP.
- hand.bin: ArduPilot DataFlash (FMT, PARM with the IMU correction's parameters at their defaults,
  then IMU with instance I = 0, LogStructure.h's formats), each
  message packed by pymavlink's DFMessage.get_msgbuf (the packer mavlogdump writes .bin files with;
  pymavlink has no log-writer class), and the file read back with pymavlink's DFReader_binary,
  which must give the same values.
- hand-accgyr.bin: ArduPilot DataFlash as a batch-sampling log writes it: FMT, then ACC and GYR
  (no IMU message, no temperature) for two instances, the session's first ACCGYR_ROWS rows as
  I = 0 and the same with 0.25 m/s² added to AccX as I = 1; packed and read back as hand.bin.
- hand.mcap: a ROS 2 bag written by mcap-ros2-support's Writer (zstd chunks, CDR), topic /imu/data,
  sensor_msgs/msg/Imu with header.stamp the sample time.

expected.json holds, per file, the first and last three samples as the reference tool read them back
(time s, acc m/s², gyro rad/s), for host's readers to match.
"""
import json
import shutil
import struct
import sys
from pathlib import Path

import numpy as np

ROWS = 6000
DROP = 3000


def read_session(csv_path):
    data = np.loadtxt(csv_path, delimiter=",", skiprows=1, max_rows=ROWS)
    t = data[:, 0]
    acc = data[:, 1:4]
    gyro = data[:, 4:7]
    temp = 24.0 + 0.6 * (t - t[0]) / (t[-1] - t[0])
    return t, acc, gyro, temp


def samples(t, acc, gyro):
    """The first and last three samples, float32 as the logs hold them."""
    idx = [0, 1, 2, len(t) - 3, len(t) - 2, len(t) - 1]
    f = lambda v: [float(np.float32(x)) for x in v]
    return [{"t_s": float(t[i]), "acc": f(acc[i]), "gyro": f(gyro[i])} for i in idx]


ACCEL_FORMAT = (
    "uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;float z;"
    "float temperature;uint32_t error_count;uint8_t[3] clip_counter;uint8_t samples;"
    "uint8_t[4] _padding0;"
)


def ulog_seed(path):
    """A minimal ULog (header, flag bits, the two formats, their subscriptions, one sample each) for
    pyulog to parse; its data are then replaced and pyulog writes the real file."""
    out = bytearray(b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0))
    msg = lambda ty, body: struct.pack("<HB", len(body), ord(ty)) + body
    out += msg("B", bytes(16) + struct.pack("<QQQ", 0, 0, 0))
    for name in ["sensor_accel", "sensor_gyro"]:
        out += msg("F", f"{name}:{ACCEL_FORMAT}".encode())
    for msg_id, name in enumerate(["sensor_accel", "sensor_gyro"]):
        out += msg("A", struct.pack("<BH", 0, msg_id) + name.encode())
    for msg_id in range(2):
        body = struct.pack("<HQQIffffI3BB", msg_id, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1)
        out += msg("D", body)
    path.write_bytes(bytes(out))


def write_ulog(path, t, acc, gyro, temp):
    from pyulog import ULog

    seed = path.with_suffix(".seed.ulg")
    ulog_seed(seed)
    log = ULog(str(seed))
    seed.unlink()
    keep = np.ones(len(t), bool)
    keep[DROP : DROP + 2] = False
    us = np.round(t[keep] * 1e6).astype(np.uint64) + np.uint64(1_000_000)
    for d in log.data_list:
        v = acc if d.name == "sensor_accel" else gyro
        n = int(keep.sum())
        d.data = {
            "timestamp": us + np.uint64(150),
            "timestamp_sample": us,
            "device_id": np.full(n, 0x2A0001, np.uint32),
            "x": v[keep, 0].astype(np.float32),
            "y": v[keep, 1].astype(np.float32),
            "z": v[keep, 2].astype(np.float32),
            "temperature": temp[keep].astype(np.float32),
            "error_count": np.zeros(n, np.uint32),
            "clip_counter[0]": np.zeros(n, np.uint8),
            "clip_counter[1]": np.zeros(n, np.uint8),
            "clip_counter[2]": np.zeros(n, np.uint8),
            "samples": np.ones(n, np.uint8),
        }
    dropout = ULog.MessageDropout(struct.pack("<H", 20), None, int(round(t[DROP] * 1e6)) + 1_000_000)
    log._dropouts.append(dropout)
    log.write_ulog(str(path))
    # Read back with pyulog: the same samples, and the dropout.
    back = ULog(str(path))
    a = back.get_dataset("sensor_accel").data
    g = back.get_dataset("sensor_gyro").data
    assert np.array_equal(a["x"], acc[keep, 0].astype(np.float32))
    assert np.array_equal(g["z"], gyro[keep, 2].astype(np.float32))
    assert [d.duration for d in back.dropouts] == [20]
    tt = a["timestamp_sample"] * 1e-6
    ax = np.stack([a["x"], a["y"], a["z"]], 1)
    gx = np.stack([g["x"], g["y"], g["z"]], 1)
    return samples(tt, ax, gx)


IMU_COLUMNS = "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz"
IMU_FORMAT = "QBffffffIIfBBHH"
IMU_TYPE = 0xA5


def dataflash_fmt(ty, name, form, cols):
    """An FMT message for a message type, and the type's DFFormat: both pymavlink's own."""
    from pymavlink.DFReader import DFFormat

    length = 3 + struct.calcsize("<" + form.replace("n", "4s").replace("N", "16s").replace("Z", "64s"))
    fmt_of_fmt = DFFormat(0x80, "FMT", 89, "BBnNZ", "Type,Length,Name,Format,Columns")
    fmt = dataflash_msg(fmt_of_fmt, [ty, length, name.encode(), form.encode(), cols.encode()])
    return fmt, DFFormat(ty, name, length, form, cols)


def dataflash_msg(fmt, values):
    """One message packed by pymavlink's DFMessage.get_msgbuf (what mavlogdump writes a .bin with)."""
    from pymavlink.DFReader import DFMessage

    out = DFMessage(fmt, list(values), False, None).get_msgbuf()
    assert out is not None, (fmt.name, values)
    return out


PARM_TYPE = 0x81
# The device ids of the vehicle's IMUs (instances 0 and 1).
ACC_IDS, GYR_IDS = (2753028, 2753036), (2752772, 2752780)


def dataflash_parms(instances):
    """FMT of PARM ("QNf", as ArduPilot's Write_Parameter writes it) and the parameters ArduPilot
    corrects the IMU samples with (AP_InertialSensor_Backend.cpp, _rotate_and_correct_accel), each
    at its default: the samples are the sensor's own output, as the simulation gives them."""
    fmt, parm = dataflash_fmt(PARM_TYPE, "PARM", "QNf", "TimeUS,Name,Value")
    values = [("AHRS_ORIENTATION", 0.0)]
    for i in range(instances):
        sfx = "" if i == 0 else str(i + 1)
        values += [(f"INS_ACC{sfx}_ID", float(ACC_IDS[i])), (f"INS_GYR{sfx}_ID", float(GYR_IDS[i]))]
        for axis in "XYZ":
            values += [(f"INS_ACC{sfx}OFFS_{axis}", 0.0), (f"INS_ACC{sfx}SCAL_{axis}", 1.0)]
            values += [(f"INS_GYR{sfx}OFFS_{axis}", 0.0)]
    out = bytearray(fmt)
    for name, value in values:
        out += dataflash_msg(parm, [1_000_000, name.encode(), value])
    return out


def write_dataflash(path, t, acc, gyro, temp):
    from pymavlink import DFReader

    out = bytearray()
    fmt, _ = dataflash_fmt(0x80, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns")
    imu_fmt, imu = dataflash_fmt(IMU_TYPE, "IMU", IMU_FORMAT, IMU_COLUMNS)
    out += fmt + imu_fmt + dataflash_parms(1)
    us = np.round(t * 1e6).astype(np.uint64) + np.uint64(2_000_000)
    for k in range(len(t)):
        values = [int(us[k]), 0, *map(float, gyro[k]), *map(float, acc[k]), 0, 0, float(temp[k])]
        out += dataflash_msg(imu, values + [1, 1, 100, 100])
    path.write_bytes(bytes(out))
    # Read back with pymavlink's DataFlash reader.
    log = DFReader.DFReader_binary(str(path), zero_time_base=True)
    ts, a, g, n = [], [], [], 0
    while True:
        m = log.recv_match(type="IMU")
        if m is None:
            break
        assert m.I == 0
        assert np.float32(m.AccX) == np.float32(acc[n, 0]) and np.float32(m.GyrZ) == np.float32(gyro[n, 2])
        assert abs(m.T - temp[n]) < 1e-4
        ts.append(m.TimeUS * 1e-6)
        a.append([m.AccX, m.AccY, m.AccZ])
        g.append([m.GyrX, m.GyrY, m.GyrZ])
        n += 1
    assert n == len(t), (n, len(t))
    return samples(np.array(ts), np.array(a), np.array(g))


IMU_MSGDEF = """std_msgs/Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Quaternion
float64 x 0
float64 y 0
float64 z 0
float64 w 1
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""


ACCGYR_ROWS = 1500
ACC_TYPE, GYR_TYPE = 0xA6, 0xA7


def write_dataflash_accgyr(path, t, acc, gyro):
    """ACC and GYR (LogStructure.h in AP_InertialSensor: "QBQfff", TimeUS,I,SampleUS,x,y,z)."""
    from pymavlink import DFReader

    t, acc, gyro = t[:ACCGYR_ROWS], acc[:ACCGYR_ROWS], gyro[:ACCGYR_ROWS]
    out = bytearray()
    fmt, _ = dataflash_fmt(0x80, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns")
    acc_fmt, acc_type = dataflash_fmt(ACC_TYPE, "ACC", "QBQfff", "TimeUS,I,SampleUS,AccX,AccY,AccZ")
    gyr_fmt, gyr_type = dataflash_fmt(GYR_TYPE, "GYR", "QBQfff", "TimeUS,I,SampleUS,GyrX,GyrY,GyrZ")
    out += fmt + acc_fmt + gyr_fmt + dataflash_parms(2)
    sample_us = np.round(t * 1e6).astype(np.uint64) + np.uint64(2_000_000)
    for k in range(len(t)):
        # Written 800 µs after the sample was taken, as the batch sampler does.
        written = int(sample_us[k]) + 800
        for inst, dx in ((0, 0.0), (1, 0.25)):
            a = (float(acc[k, 0] + dx), float(acc[k, 1]), float(acc[k, 2]))
            head = [written, inst, int(sample_us[k])]
            out += dataflash_msg(acc_type, head + list(a))
            out += dataflash_msg(gyr_type, head + list(map(float, gyro[k])))
    path.write_bytes(bytes(out))
    log = DFReader.DFReader_binary(str(path), zero_time_base=True)
    ts, a, g = [], [], []
    while True:
        m = log.recv_match(type=["ACC", "GYR"])
        if m is None:
            break
        if m.I != 0:
            continue
        if m.get_type() == "ACC":
            ts.append(m.SampleUS * 1e-6)
            a.append([m.AccX, m.AccY, m.AccZ])
        else:
            g.append([m.GyrX, m.GyrY, m.GyrZ])
    assert len(ts) == len(g) == len(t), (len(ts), len(g), len(t))
    assert np.all(np.float32(np.array(a)) == np.float32(acc))
    return samples(np.array(ts), np.array(a), np.array(g))


def write_mcap(path, t, acc, gyro):
    from mcap_ros2.decoder import DecoderFactory
    from mcap_ros2.writer import Writer
    from mcap.reader import make_reader

    t0 = 1_700_000_000
    with open(path, "wb") as f:
        w = Writer(f)
        schema = w.register_msgdef("sensor_msgs/msg/Imu", IMU_MSGDEF)
        for k in range(len(t)):
            ns = int(round(t[k] * 1e9))
            sec, nanosec = t0 + ns // 1_000_000_000, ns % 1_000_000_000
            # The driver's float32 values, as a real IMU gives them.
            a = [float(np.float32(x)) for x in acc[k]]
            g = [float(np.float32(x)) for x in gyro[k]]
            msg = {
                "header": {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": "imu_link"},
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                "orientation_covariance": [-1.0] + [0.0] * 8,
                "angular_velocity": {"x": g[0], "y": g[1], "z": g[2]},
                "angular_velocity_covariance": [0.0] * 9,
                "linear_acceleration": {"x": a[0], "y": a[1], "z": a[2]},
                "linear_acceleration_covariance": [0.0] * 9,
            }
            # The recorder receives each message a few ms after its stamp.
            log_ns = t0 * 1_000_000_000 + ns + 3_000_000
            w.write_message("/imu/data", schema, msg, log_time=log_ns, publish_time=log_ns)
        w.finish()
    ts, a, g = [], [], []
    with open(path, "rb") as f:
        for _, _, _, m in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            ts.append(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9)
            v = m.linear_acceleration
            a.append([v.x, v.y, v.z])
            v = m.angular_velocity
            g.append([v.x, v.y, v.z])
    assert len(ts) == len(t)
    return samples(np.array(ts), np.array(a), np.array(g))


def main():
    csv_path, out_dir = Path(sys.argv[1]), Path(sys.argv[2])
    out_dir.mkdir(parents=True, exist_ok=True)
    t, acc, gyro, temp = read_session(csv_path)
    expected = {
        "hand.ulg": write_ulog(out_dir / "hand.ulg", t, acc, gyro, temp),
        "hand.bin": write_dataflash(out_dir / "hand.bin", t, acc, gyro, temp),
        "hand-accgyr.bin": write_dataflash_accgyr(out_dir / "hand-accgyr.bin", t, acc, gyro),
        "hand.mcap": write_mcap(out_dir / "hand.mcap", t, acc, gyro),
        "rows": ROWS,
    }
    (out_dir / "expected.json").write_text(json.dumps(expected, indent=1) + "\n")
    shutil.copy(csv_path.with_suffix(".truth.toml"), out_dir / "hand.truth.toml")
    for p in sorted(out_dir.iterdir()):
        print(f"{p}: {p.stat().st_size} bytes")


if __name__ == "__main__":
    main()
