#!/usr/bin/env node
// Writes a ROS 2 bag as MCAP with the reference TypeScript library (@mcap/core), the way
// rosbag2's mcap storage plugin lays it out (profile "ros2", schema encoding "ros2msg", message
// encoding "cdr"), from messages dumped by a test (the serialized CDR messages of a sqlite3 bag).
//
// usage: node write_ros2_mcap.cjs DUMP OUT.mcap [--compression none|zstd|lz4] [--no-chunks]
//        [--no-index] [--chunk-size BYTES]
// DUMP: records of  u32 topic length, topic, u32 type length, type, u64 log time (ns),
//       u32 data length, data  (little endian), in recording order.
"use strict";

const fs = require("fs");
const path = require("path");
const { createRequire } = require("module");

const toolsDir =
  process.env.RINGTRACK_MCAP_CHECK_MODULES ||
  path.join(__dirname, "..", "..", "tools", "mcap-check");
const requireTool = createRequire(path.join(toolsDir, "package.json"));
const { McapWriter } = requireTool("@mcap/core");
const zstd = requireTool("@foxglove/wasm-zstd");
const lz4js = requireTool("lz4js");

// Message definitions as rosbag2 stores them (the .msg text; nested types follow after "===").
const definitions = {
  "velodyne_msgs/msg/VelodyneScan":
    "std_msgs/Header header\nVelodynePacket[] packets\n" +
    "================================================================================\n" +
    "MSG: velodyne_msgs/VelodynePacket\nbuiltin_interfaces/Time stamp\nuint8[1206] data\n",
  "pandar_msgs/msg/PandarScan":
    "std_msgs/Header header\nPandarPacket[] packets\n" +
    "================================================================================\n" +
    "MSG: pandar_msgs/PandarPacket\nbuiltin_interfaces/Time stamp\nuint8[1500] data\nuint32 size\n",
};

function fail(what) {
  process.stderr.write(`write_ros2_mcap: ${what}\n`);
  process.exit(1);
}

class FileWritable {
  constructor(file) {
    this.fd = fs.openSync(file, "w");
    this.offset = 0n;
  }
  async write(buffer) {
    fs.writeSync(this.fd, buffer);
    this.offset += BigInt(buffer.byteLength);
  }
  position() {
    return this.offset;
  }
  close() {
    fs.closeSync(this.fd);
  }
}

function parseDump(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const text = (at, n) => Buffer.from(bytes.subarray(at, at + n)).toString("utf8");
  const out = [];
  let at = 0;
  while (at < bytes.length) {
    const topicLength = view.getUint32(at, true);
    const topic = text(at + 4, topicLength);
    at += 4 + topicLength;
    const typeLength = view.getUint32(at, true);
    const type = text(at + 4, typeLength);
    at += 4 + typeLength;
    const logTime = view.getBigUint64(at, true);
    const dataLength = view.getUint32(at + 8, true);
    const data = bytes.subarray(at + 12, at + 12 + dataLength);
    at += 12 + dataLength;
    out.push({ topic, type, logTime, data });
  }
  return out;
}

async function main() {
  const [dumpFile, outFile, ...rest] = process.argv.slice(2);
  if (!dumpFile || !outFile) fail("usage: write_ros2_mcap.cjs DUMP OUT.mcap [options]");
  let compression = "zstd";
  let chunks = true;
  let index = true;
  let chunkSize = 1024 * 1024;
  for (let i = 0; i < rest.length; i++) {
    if (rest[i] === "--compression") compression = rest[++i];
    else if (rest[i] === "--no-chunks") chunks = false;
    else if (rest[i] === "--no-index") index = false;
    else if (rest[i] === "--chunk-size") chunkSize = Number(rest[++i]);
    else fail(`unknown option ${rest[i]}`);
  }
  await zstd.isLoaded;
  const compressChunk =
    compression === "zstd"
      ? (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) })
      : compression === "lz4"
        ? (data) => ({ compression: "lz4", compressedData: lz4js.compress(data) })
        : undefined;
  const writable = new FileWritable(outFile);
  const writer = new McapWriter({
    writable,
    useChunks: chunks,
    chunkSize,
    compressChunk,
    useStatistics: index,
    useSummaryOffsets: index,
    useChunkIndex: index && chunks,
    useMessageIndex: index && chunks,
    useMetadataIndex: index,
    useAttachmentIndex: index,
    repeatSchemas: index,
    repeatChannels: index,
  });
  await writer.start({ profile: "ros2", library: "@mcap/core (ringtrack tests)" });
  const channels = new Map();
  let sequence = 0;
  for (const m of parseDump(new Uint8Array(fs.readFileSync(dumpFile)))) {
    let channelId = channels.get(m.topic);
    if (channelId === undefined) {
      const schemaId = await writer.registerSchema({
        name: m.type, encoding: "ros2msg",
        data: new TextEncoder().encode(definitions[m.type] || "") });
      channelId = await writer.registerChannel({
        topic: m.topic, schemaId, messageEncoding: "cdr",
        metadata: new Map([["offered_qos_profiles", ""]]) });
      channels.set(m.topic, channelId);
    }
    await writer.addMessage({ channelId, sequence: sequence++, logTime: m.logTime,
                              publishTime: m.logTime, data: m.data });
  }
  await writer.end();
  writable.close();
}

main().catch((e) => fail(e && e.message ? e.message : String(e)));
