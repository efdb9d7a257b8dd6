#!/usr/bin/python3
# Seeds for fuzz/fuzz_mcap_reader.cpp: small complete MCAP files (one chunk of a schema, a channel
# and three messages; its Message Index; a Metadata record; Data End with the data CRC; a summary
# with Statistics, Chunk and Metadata Indexes; the summary CRC), one per chunk compression (none,
# lz4 and zstd, by the zstd and lz4 command-line tools), each behind the target's control byte
# (0: read with the summary, 2: without). Without them the fuzzer seldom builds a valid lz4 or
# zstd frame, so decompression and the index paths stay unexplored. The files pass @mcap/core
# (tests/mcap/validate_mcap.cjs). Usage: make_fuzz_seeds.py OUTPUT_FOLDER
import os
import struct
import subprocess
import sys
import zlib

out = sys.argv[1]
MAGIC = b"\x89MCAP0\r\n"
def rec(op, body): return bytes([op]) + struct.pack("<Q", len(body)) + body
def s(x): x = x.encode(); return struct.pack("<I", len(x)) + x
def compress(kind, data):
    if kind == "": return data
    cmd = ["zstd", "-q", "-c", "--fast=3"] if kind == "zstd" else ["lz4", "-q", "-c", "--content-size"]
    return subprocess.run(cmd, input=data, capture_output=True, check=True).stdout
def mcap(kind, messages=3):
    f = MAGIC + rec(1, s("ros2") + s("seed"))
    schema = rec(3, struct.pack("<H", 1) + s("pkg/msg/A") + s("ros2msg") + struct.pack("<I", 3) + b"int")
    meta = s("k") + s("v")
    channel = rec(4, struct.pack("<HH", 0, 1) + s("/a") + s("cdr") + struct.pack("<I", len(meta)) + meta)
    records = schema + channel
    offsets = []
    for k in range(messages):
        offsets.append(len(records))
        records += rec(5, struct.pack("<HIQQ", 0, k, 100 + k, 100 + k) + bytes([k]) * (5 + 7 * k))
    data = compress(kind, records)
    chunk_at = len(f)
    chunk = rec(6, struct.pack("<QQQI", 100, 99 + messages, len(records), zlib.crc32(records)) + s(kind) +
                struct.pack("<Q", len(data)) + data)
    f += chunk
    index_at = len(f)
    entries = b"".join(struct.pack("<QQ", 100 + k, o) for k, o in enumerate(offsets))
    index = rec(7, struct.pack("<H", 0) + struct.pack("<I", len(entries)) + entries)
    f += index
    meta_at = len(f)
    metadata = rec(12, s("info") + struct.pack("<I", len(meta)) + meta)
    f += metadata
    f += rec(15, struct.pack("<I", zlib.crc32(f)))
    summary_start = len(f)
    counts = struct.pack("<HQ", 0, messages)
    summary = schema + channel
    summary += rec(11, struct.pack("<QHIIIIQQ", messages, 1, 1, 0, 1, 1, 100, 99 + messages) +
                   struct.pack("<I", len(counts)) + counts)
    offs = struct.pack("<HQ", 0, index_at)
    summary += rec(8, struct.pack("<QQQQ", 100, 99 + messages, chunk_at, len(chunk)) +
                   struct.pack("<I", len(offs)) + offs + struct.pack("<Q", len(index)) + s(kind) +
                   struct.pack("<QQ", len(data), len(records)))
    summary += rec(13, struct.pack("<QQ", meta_at, len(metadata)) + s("info"))
    f += summary
    footer = bytes([2]) + struct.pack("<QQQ", 20, summary_start, 0)
    f += footer + struct.pack("<I", zlib.crc32(summary + footer)) + MAGIC
    return f
for kind in ["", "lz4", "zstd"]:
    for control in [0, 2]:
        name = (kind or "none") + "_" + str(control)
        open(os.path.join(out, name), "wb").write(bytes([control]) + mcap(kind))
