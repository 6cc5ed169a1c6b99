#!/usr/bin/env python3
"""Writes the fuzz targets' seed inputs (fuzz/seeds/TARGET/) from the test data.

Run from the repository root with the test venv (it needs the `mcap` package):
    .venv/bin/python fuzz/make_seeds.py
The output is deterministic and committed; rerun it when the test data or a format
changes. Device byte streams are built here from the protocols (docs/devices.md).
"""

import io
import os
import shutil
import struct

from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SEEDS = os.path.join(ROOT, "fuzz", "seeds")
TESTDATA = os.path.join(ROOT, "testdata")
FIXTURES = os.path.join(ROOT, "crates", "ekf-cli", "tests", "fixtures")


def target_dir(name):
    path = os.path.join(SEEDS, name)
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)
    return path


def write(directory, name, data):
    with open(os.path.join(directory, name), "wb") as f:
        f.write(data)


def first_messages(bag, per_topic):
    """The first `per_topic` messages of each topic: (schema, channel, message)."""
    seen = {}
    with open(bag, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            if seen.get(channel.topic, 0) < per_topic:
                seen[channel.topic] = seen.get(channel.topic, 0) + 1
                yield schema, channel, message


def cdr_seeds():
    out = target_dir("cdr_message")
    for bag in ("sim-paper.mcap", "aces.mcap"):
        for i, (_, channel, message) in enumerate(first_messages(os.path.join(TESTDATA, bag), 2)):
            topic = channel.topic.strip("/").replace("/", "_")
            write(out, f"{bag[:-5]}-{topic}-{i}", message.data)


def small_bag(compression, chunk_size):
    """The first messages of sim-paper.mcap in a small bag with several chunks."""
    buf = io.BytesIO()
    writer = Writer(buf, chunk_size=chunk_size, compression=compression)
    writer.start(profile="ros2", library="ekf fuzz seeds")
    schemas, channels = {}, {}
    for schema, channel, message in first_messages(os.path.join(TESTDATA, "sim-paper.mcap"), 3):
        if schema.id not in schemas:
            schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
        if channel.id not in channels:
            channels[channel.id] = writer.register_channel(
                channel.topic, channel.message_encoding, schemas[schema.id], channel.metadata
            )
        writer.add_message(
            channels[channel.id], message.log_time, message.data, message.publish_time, message.sequence
        )
    writer.finish()
    return buf.getvalue()


def mcap_seeds():
    out = target_dir("mcap_bag")
    whole = small_bag(CompressionType.NONE, 2048)
    write(out, "uncompressed.mcap", whole)
    write(out, "zstd.mcap", small_bag(CompressionType.ZSTD, 2048))
    write(out, "lz4.mcap", small_bag(CompressionType.LZ4, 2048))
    # A recording cut short: no summary, the last chunk broken off.
    write(out, "cut.mcap", whole[: len(whole) * 2 // 3])


def sick_crc(data):
    """The LMS 2xx CRC-16 (generator 0x8005, two-byte window), as in sick/crc.rs."""
    crc, previous = 0, 0
    for byte in data:
        crc = (((crc & 0x7FFF) << 1) ^ 0x8005) if crc & 0x8000 else (crc << 1)
        crc = (crc ^ (byte | (previous << 8))) & 0xFFFF
        previous = byte
    return crc


def sick_telegram(address, command, data):
    body = bytes([0x02, address]) + struct.pack("<H", len(data) + 1) + bytes([command]) + data
    return body + struct.pack("<H", sick_crc(body))


def sick_seeds():
    out = target_dir("sick_telegrams")
    # Split byte first (see the target), then the stream.
    mode_reply = sick_telegram(0x80, 0xA0, bytes([0x00, 0x10]))
    ranges = bytes(struct.pack("<H", 181)) + b"".join(
        struct.pack("<H", 500 + (i * 37) % 4000) for i in range(181)
    )
    scan = sick_telegram(0x80, 0xB0, ranges + bytes([0x10]))
    write(out, "ack-mode-scan", bytes([40]) + b"\x06" + mode_reply + scan)
    write(out, "noise-nak-scan", bytes([200]) + b"\xff\x02\x00" + b"\x15" + scan)
    write(out, "request", bytes([3]) + sick_telegram(0x00, 0x20, bytes([0x24])))


def modbus_crc(data):
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return struct.pack("<H", crc)


def modbus_seeds():
    out = target_dir("modbus_reply")
    request = bytes([1, 0x04, 0, 0, 0, 6])
    request += modbus_crc(request)
    registers = struct.pack(">6H", 0x0001, 0x2345, 0xFFFF, 0xFF00, 1234, 7)
    reply = bytes([1, 0x04, len(registers)]) + registers
    reply += modbus_crc(reply)
    exception = bytes([1, 0x84, 0x02])
    exception += modbus_crc(exception)
    write(out, "reply", bytes([5]) + reply)
    write(out, "echo-noise-reply", bytes([9]) + request + b"\x55\x01\x04" + reply)
    write(out, "exception", bytes([1]) + exception)


def nmea(sentence):
    checksum = 0
    for c in sentence.encode():
        checksum ^= c
    return f"${sentence}*{checksum:02X}\r\n".encode()


def nmea_seeds():
    out = target_dir("nmea_sentences")
    gga = nmea("GPGGA,123519.00,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,")
    rmc = nmea("GPRMC,123520.00,A,4807.040,N,01131.002,E,0.5,84.4,230394,003.1,W")
    nofix = nmea("GPGGA,123521.00,,,,,0,00,99.9,,M,,M,,")
    write(out, "gga-rmc", bytes([30]) + gga + rmc)
    write(out, "nofix-garbage", bytes([4]) + nofix + b"$GPGGA,bad*00\r\n")


def text_seeds(target, sources):
    out = target_dir(target)
    for name, path, max_lines in sources:
        with open(path, "rb") as f:
            lines = f.read().splitlines(keepends=True)
        write(out, name, b"".join(lines[:max_lines]))


def main():
    cdr_seeds()
    mcap_seeds()
    sick_seeds()
    modbus_seeds()
    nmea_seeds()
    text_seeds("carmen_log", [("corrected.log", os.path.join(FIXTURES, "carmen_corrected.log"), 200)])
    text_seeds(
        "mrpt_log",
        [
            ("excerpt.txt", os.path.join(FIXTURES, "mrpt_excerpt.txt"), 40),
            ("scans.txt", os.path.join(TESTDATA, "mrpt-scans-excerpt.txt"), 20),
        ],
    )
    text_seeds(
        "config_toml",
        [
            ("default.toml", os.path.join(ROOT, "crates", "ekf-ros", "src", "default_config.toml"), 10_000),
            ("paper-robot.toml", os.path.join(ROOT, "crates", "ekf-ros", "presets", "paper-robot.toml"), 10_000),
        ],
    )
    text_seeds(
        "map_json",
        [
            ("paper-room.json", os.path.join(TESTDATA, "paper-room.json"), 10_000),
            ("aces-map.json", os.path.join(TESTDATA, "aces-map.json"), 60),
        ],
    )
    text_seeds(
        "tum_trajectory",
        [
            ("evo_est.txt", os.path.join(ROOT, "crates", "ekf-cli", "tests", "golden", "evo_est.txt"), 50),
            ("evo_ref.txt", os.path.join(ROOT, "crates", "ekf-cli", "tests", "golden", "evo_ref.txt"), 50),
        ],
    )


if __name__ == "__main__":
    main()
