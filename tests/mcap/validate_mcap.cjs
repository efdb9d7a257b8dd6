#!/usr/bin/env node
// Independent check of an MCAP file with the reference TypeScript library (@mcap/core), used by
// ringtrack's tests: reads the file twice, linearly (McapStreamReader: magic, every record, chunk
// CRCs) and through its summary (McapIndexedReader: footer, summary CRC, chunk and message
// indexes), checks the data section CRC, that both readings give the same messages, that the
// Statistics and indexes agree with what is in the file, and decodes the protobuf messages with
// protobufjs from the FileDescriptorSet embedded in each schema.
//
// usage: node validate_mcap.cjs FILE.mcap   -> prints one JSON object on stdout, exits 0;
//        on any inconsistency prints "validate_mcap: <what>" on stderr and exits 1.
// The node modules come from tools/mcap-check (scripts/bootstrap installs them) or from
// $RINGTRACK_MCAP_CHECK_MODULES.
"use strict";

const fs = require("fs");
const path = require("path");
const { createRequire } = require("module");

const toolsDir =
  process.env.RINGTRACK_MCAP_CHECK_MODULES ||
  path.join(__dirname, "..", "..", "tools", "mcap-check");
const requireTool = createRequire(path.join(toolsDir, "package.json"));
const { McapStreamReader, McapIndexedReader } = requireTool("@mcap/core");
const { crc32 } = requireTool("@foxglove/crc");
const zstd = requireTool("@foxglove/wasm-zstd");
const lz4 = requireTool("@foxglove/wasm-lz4");
const protobuf = requireTool("protobufjs");
const descriptor = requireTool("protobufjs/ext/descriptor");

function fail(what) {
  process.stderr.write(`validate_mcap: ${what}\n`);
  process.exit(1);
}

function check(condition, what) {
  if (!condition) fail(what);
}

const decompressHandlers = {
  zstd: (data, size) => zstd.decompress(data, Number(size)),
  lz4: (data, size) => lz4.default ? lz4.default(data, Number(size)) : lz4(data, Number(size)),
};

function messageKey(m) {
  return `${m.channelId}/${m.sequence}/${m.logTime}`;
}

async function main() {
  const file = process.argv[2];
  if (!file) fail("usage: validate_mcap.cjs FILE.mcap");
  await zstd.isLoaded;
  await (lz4.default ? lz4.default.isLoaded : lz4.isLoaded);
  const bytes = new Uint8Array(fs.readFileSync(file));

  // 1. Linear reading: every record, chunk CRCs validated by the library.
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true, includeChunks: true });
  stream.append(bytes);
  const linear = { schemas: new Map(), channels: new Map(), messages: [], metadata: [], chunks: [],
                   messageIndexes: 0, dataEnd: undefined, header: undefined, footer: undefined,
                   statistics: [] };
  let inSummary = false;
  for (let record; (record = stream.nextRecord()); ) {
    switch (record.type) {
      case "Header": linear.header = record; break;
      case "Schema": if (!inSummary) linear.schemas.set(record.id, record); break;
      case "Channel": if (!inSummary) linear.channels.set(record.id, record); break;
      case "Message": linear.messages.push(record); break;
      case "Metadata": linear.metadata.push(record); break;
      case "Chunk": linear.chunks.push(record); break;
      case "MessageIndex": linear.messageIndexes++; break;
      case "DataEnd": linear.dataEnd = record; inSummary = true; break;
      case "Statistics": linear.statistics.push(record); break;
      case "Footer": linear.footer = record; break;
      default: break;
    }
  }
  check(stream.done(), "the linear reading did not reach the trailing magic");
  check(linear.header !== undefined, "no Header record");
  check(linear.dataEnd !== undefined, "no Data End record");
  check(linear.footer !== undefined, "no Footer record");

  // 2. Indexed reading: footer, summary (its CRC checked by the library), indexes.
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
  const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  check(linear.footer.summaryCrc !== 0, "the footer has no summary CRC");

  // Data section CRC: every byte before the Data End record.
  const dataCrc = crc32(bytes.subarray(0, Number(indexed.dataEndOffset)));
  check(linear.dataEnd.dataSectionCrc !== 0, "the Data End record has no data section CRC");
  check(dataCrc === linear.dataEnd.dataSectionCrc,
        `data section CRC ${dataCrc} but the Data End record says ${linear.dataEnd.dataSectionCrc}`);

  // Chunk CRCs present, chunk indexes pointing at the chunks, message indexes covering them.
  for (const c of linear.chunks) check(c.uncompressedCrc !== 0, "a chunk without CRC");
  check(indexed.chunkIndexes.length === linear.chunks.length,
        `${indexed.chunkIndexes.length} chunk indexes for ${linear.chunks.length} chunks`);
  let indexedMessages = 0;
  for (const ci of indexed.chunkIndexes) {
    const view = new DataView(bytes.buffer, bytes.byteOffset);
    check(bytes[Number(ci.chunkStartOffset)] === 0x06,
          `chunk index points at offset ${ci.chunkStartOffset}, which is no Chunk record`);
    const length = view.getBigUint64(Number(ci.chunkStartOffset) + 1, true) + 9n;
    check(length === ci.chunkLength, `chunk at ${ci.chunkStartOffset}: length ${length}, index says ${ci.chunkLength}`);
    let indexBytes = 0n;
    for (const [, offset] of ci.messageIndexOffsets) {
      check(bytes[Number(offset)] === 0x07, `message index offset ${offset} is no Message Index record`);
      const recordLength = view.getBigUint64(Number(offset) + 1, true) + 9n;
      indexBytes += recordLength;
      const entriesBytes = view.getUint32(Number(offset) + 11, true);
      indexedMessages += entriesBytes / 16;
    }
    check(indexBytes === ci.messageIndexLength,
          `chunk at ${ci.chunkStartOffset}: message indexes of ${indexBytes} bytes, index says ${ci.messageIndexLength}`);
  }
  check(indexedMessages === linear.messages.length,
        `message indexes list ${indexedMessages} messages, the chunks hold ${linear.messages.length}`);

  // Both readings give the same messages.
  const viaIndex = [];
  for await (const m of indexed.readMessages({ validateCrcs: true })) viaIndex.push(m);
  check(viaIndex.length === linear.messages.length,
        `${viaIndex.length} messages through the index, ${linear.messages.length} linearly`);
  const linearByKey = new Map(linear.messages.map((m) => [messageKey(m), m]));
  for (const m of viaIndex) {
    const l = linearByKey.get(messageKey(m));
    check(l !== undefined, `message ${messageKey(m)} found through the index only`);
    check(Buffer.compare(Buffer.from(l.data), Buffer.from(m.data)) === 0,
          `message ${messageKey(m)} differs between the readings`);
  }

  // Statistics agree with the file.
  const stats = indexed.statistics;
  check(stats !== undefined, "no Statistics record");
  check(stats.messageCount === BigInt(linear.messages.length), "Statistics message_count is wrong");
  check(stats.schemaCount === linear.schemas.size, "Statistics schema_count is wrong");
  check(stats.channelCount === linear.channels.size, "Statistics channel_count is wrong");
  check(stats.chunkCount === linear.chunks.length, "Statistics chunk_count is wrong");
  check(stats.metadataCount === linear.metadata.length, "Statistics metadata_count is wrong");
  const perChannel = new Map();
  let minTime, maxTime;
  for (const m of linear.messages) {
    perChannel.set(m.channelId, (perChannel.get(m.channelId) || 0n) + 1n);
    if (minTime === undefined || m.logTime < minTime) minTime = m.logTime;
    if (maxTime === undefined || m.logTime > maxTime) maxTime = m.logTime;
  }
  for (const [id, count] of stats.channelMessageCounts) {
    check((perChannel.get(id) || 0n) === count, `Statistics count of channel ${id} is wrong`);
  }
  if (minTime !== undefined) {
    check(stats.messageStartTime === minTime && stats.messageEndTime === maxTime,
          "Statistics time range is wrong");
  }
  // Summary copies of schemas and channels equal the data section's.
  check(indexed.schemasById.size === linear.schemas.size, "summary schemas differ");
  check(indexed.channelsById.size === linear.channels.size, "summary channels differ");
  check(indexed.metadataIndexes.length === linear.metadata.length, "metadata indexes differ");
  const metadata = {};
  for await (const m of indexed.readMetadata()) metadata[m.name] = Object.fromEntries(m.metadata);

  // Decode every protobuf message with the schema's own FileDescriptorSet.
  const types = new Map();
  for (const [id, s] of indexed.schemasById) {
    if (s.encoding !== "protobuf") continue;
    const set = descriptor.FileDescriptorSet.decode(s.data);
    const root = protobuf.Root.fromDescriptor(set);
    types.set(id, root.lookupType(s.name));
  }
  const topics = {};
  const decoded = {};
  for (const m of linear.messages) {
    const channel = linear.channels.get(m.channelId);
    topics[channel.topic] = (topics[channel.topic] || 0) + 1;
    const type = types.get(channel.schemaId);
    if (type === undefined) continue;
    const object = type.toObject(type.decode(m.data), { longs: String, enums: String, defaults: true });
    (decoded[channel.topic] = decoded[channel.topic] || []).push(summarize(type.fullName, object, m));
  }

  const out = {
    profile: linear.header.profile,
    library: linear.header.library,
    messages: linear.messages.length,
    chunks: linear.chunks.length,
    compression: [...new Set(linear.chunks.map((c) => c.compression))],
    schemas: [...indexed.schemasById.values()].map((s) => ({ id: s.id, name: s.name, encoding: s.encoding })),
    channels: [...indexed.channelsById.values()].map((c) => ({
      id: c.id, topic: c.topic, schema: indexed.schemasById.get(c.schemaId)?.name ?? "",
      encoding: c.messageEncoding, messages: Number(stats.channelMessageCounts.get(c.id) || 0n) })),
    topics,
    metadata,
    decoded,
  };
  process.stdout.write(JSON.stringify(out) + "\n");
}

// What the tests compare: clouds by their layout and labels, scenes by entity, transforms.
function summarize(typeName, o, m) {
  const stamp = (t) => (t ? (BigInt(t.seconds) * 1000000000n + BigInt(t.nanos)).toString() : "0");
  const base = { log_time: m.logTime.toString() };
  if (typeName === ".foxglove.PointCloud") {
    const data = Buffer.from(o.data, "base64");
    const stride = o.point_stride;
    const fields = o.fields.map((f) => ({ name: f.name, offset: f.offset, type: f.type }));
    const points = stride > 0 ? data.length / stride : 0;
    const trackField = fields.find((f) => f.name === "track_id");
    const tracks = {};
    if (trackField) {
      for (let i = 0; i < points; i++) {
        const id = data.readUInt32LE(i * stride + trackField.offset);
        if (id !== 0) tracks[id] = (tracks[id] || 0) + 1;
      }
    }
    const first = points > 0 ? [data.readFloatLE(0), data.readFloatLE(4), data.readFloatLE(8)] : [];
    return { ...base, stamp: stamp(o.timestamp), frame_id: o.frame_id, stride, fields, points,
             whole_points: Number.isInteger(points), track_points: tracks, first_point: first };
  }
  if (typeName === ".foxglove.SceneUpdate") {
    return { ...base,
      deletions: o.deletions.map((d) => d.type),
      entities: o.entities.map((e) => ({
        id: e.id, stamp: stamp(e.timestamp), frame_id: e.frame_id,
        metadata: Object.fromEntries(e.metadata.map((kv) => [kv.key, kv.value])),
        cubes: e.cubes.map((c) => ({ center: [c.pose.position.x, c.pose.position.y, c.pose.position.z],
                                     size: [c.size.x, c.size.y, c.size.z], color: c.color })),
        arrows: e.arrows.map((a) => ({ position: [a.pose.position.x, a.pose.position.y, a.pose.position.z],
                                       length: a.shaft_length })),
        lines: e.lines.map((l) => l.points.length),
        texts: e.texts.map((t) => t.text) })) };
  }
  if (typeName === ".foxglove.FrameTransform") {
    return { ...base, stamp: stamp(o.timestamp), parent: o.parent_frame_id, child: o.child_frame_id,
             translation: [o.translation.x, o.translation.y, o.translation.z],
             rotation: [o.rotation.x, o.rotation.y, o.rotation.z, o.rotation.w] };
  }
  return base;
}

main().catch((e) => fail(e && e.message ? e.message : String(e)));
