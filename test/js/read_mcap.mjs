// An independent reader for the project's MCAP files: Foxglove's @mcap/core (indexed and
// stream readers, CRCs validated) with @foxglove/rosmsg2-serialization decoding every message.
// Usage: node read_mcap.mjs FILE... ; prints one JSON object per file on stdout.
import { McapIndexedReader, McapStreamReader } from '@mcap/core';
import { parse } from '@foxglove/rosmsg';
import { MessageReader } from '@foxglove/rosmsg2-serialization';
import { decompress as zstdDecompress } from 'fzstd';
import lz4 from 'lz4js';
import { open, readFile } from 'node:fs/promises';

const decompressHandlers = {
  zstd: (data, size) => zstdDecompress(data, new Uint8Array(Number(size))),
  lz4: (data, size) => Uint8Array.from(lz4.decompress(data, Number(size))),  // LZ4 frames
};

function summarize(value) {
  // First Float64 field of a message (std_msgs/Float64 data) or the statuses' levels.
  if (typeof value?.data === 'number') return value.data;
  if (Array.isArray(value?.status)) return value.status.map((s) => [s.name, s.level]);
  if (value?.data && value?.layout) return Array.from(value.data).length;
  return null;
}

async function indexed(path) {
  const handle = await open(path, 'r');
  const size = BigInt((await handle.stat()).size);
  const readable = {
    size: async () => size,
    read: async (offset, length) => {
      const buf = new Uint8Array(Number(length));
      await handle.read(buf, 0, Number(length), Number(offset));
      return buf;
    },
  };
  try {
    const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    const readers = new Map();
    for (const [id, ch] of reader.channelsById) {
      const schema = reader.schemasById.get(ch.schemaId);
      const defs = parse(new TextDecoder().decode(schema.data), { ros2: true });
      readers.set(id, new MessageReader(defs));
    }
    const counts = {};
    const first = {};
    const last = {};
    for await (const msg of reader.readMessages({ validateCrcs: true })) {
      const topic = reader.channelsById.get(msg.channelId).topic;
      const decoded = readers.get(msg.channelId).readMessage(msg.data);
      counts[topic] = (counts[topic] ?? 0) + 1;
      if (!(topic in first)) first[topic] = summarize(decoded);
      last[topic] = summarize(decoded);
    }
    const stats = reader.statistics;
    return {
      counts,
      first,
      last,
      statistics_messages: stats ? Number(stats.messageCount) : null,
      chunks: reader.chunkIndexes.length,
    };
  } finally {
    await handle.close();
  }
}

function streamed(bytes) {
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  reader.append(bytes);
  let messages = 0;
  let footer = false;
  for (let rec; (rec = reader.nextRecord()); ) {
    if (rec.type === 'Message') messages += 1;
    if (rec.type === 'Footer') footer = true;
  }
  return { messages, footer, done: reader.done() };
}

for (const path of process.argv.slice(2)) {
  const out = { path };
  try {
    out.indexed = await indexed(path);
  } catch (err) {
    out.indexed_error = String(err?.message ?? err);
  }
  try {
    out.stream = streamed(new Uint8Array(await readFile(path)));
  } catch (err) {
    out.stream_error = String(err?.message ?? err);
  }
  console.log(JSON.stringify(out));
}
