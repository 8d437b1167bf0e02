// Reads an MCAP file with the MCAP project's own TypeScript reader (@mcap/core, installed by
// export_mcap.sh into the build directory) twice — indexed (summary, chunk and message
// indexes, summary and chunk CRCs checked) and streamed front to back (chunk CRCs checked) —
// checks both see the same messages and the data section's CRC (with @foxglove/crc, the
// reader's own CRC), decodes every message as JSON and writes what it found as JSON.
// Usage: node mcap_read.js FILE.mcap OUT.json
"use strict";
const fs = require("fs");
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { crc32 } = require("@foxglove/crc");

function fail(msg) {
  console.error("mcap_read: " + msg);
  process.exit(1);
}

async function main() {
  const [file, out] = process.argv.slice(2);
  const bytes = new Uint8Array(fs.readFileSync(file));

  // Indexed: what Foxglove does with a seekable file.
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
  const indexed = await McapIndexedReader.Initialize({ readable });
  if (indexed.chunkIndexes.length === 0) fail("no chunk indexes");
  const byIndex = [];
  for await (const m of indexed.readMessages({ validateCrcs: true })) byIndex.push(m);

  // Streamed: every record in file order.
  const stream = new McapStreamReader({ validateCrcs: true });
  stream.append(bytes);
  const schemas = new Map(), channels = new Map(), messages = [];
  let header, footer, dataEnd, statistics, records = 0;
  for (let r; (r = stream.nextRecord()); ) {
    records++;
    if (r.type === "Header") header = r;
    else if (r.type === "Schema") schemas.set(r.id, r);
    else if (r.type === "Channel") channels.set(r.id, r);
    else if (r.type === "Message") messages.push(r);
    else if (r.type === "DataEnd") dataEnd = r;
    else if (r.type === "Statistics") statistics = r;
    else if (r.type === "Footer") footer = r;
  }
  if (!stream.done()) fail("the stream reader did not reach the end of the file");
  if (!header || !footer || !dataEnd) fail("header, data end or footer missing");

  // The data section's CRC: every byte before the Data End record, which ends where the summary starts.
  const dataEndAt = Number(footer.summaryStart) - 13;
  if (bytes[dataEndAt] !== 0x0f) fail(`no Data End record at ${dataEndAt}`);
  const crc = crc32(bytes.subarray(0, dataEndAt));
  if (dataEnd.dataSectionCrc === 0 || crc !== dataEnd.dataSectionCrc)
    fail(`data section CRC ${dataEnd.dataSectionCrc}, computed ${crc}`);

  // Indexed and streamed readers agree on every message.
  const key = (m) => `${m.channelId}/${m.sequence}/${m.logTime}/${m.publishTime}/${Buffer.from(m.data).toString("hex")}`;
  const a = byIndex.map(key).sort(), b = messages.map(key).sort();
  if (a.length !== b.length || a.some((k, i) => k !== b[i]))
    fail(`indexed reader saw ${a.length} messages, stream reader ${b.length}, or different ones`);
  if (statistics.messageCount !== BigInt(messages.length)) fail(`statistics say ${statistics.messageCount} messages`);

  const decoder = new TextDecoder("utf-8", { fatal: true });
  const result = {
    library: header.library,
    records,
    chunks: indexed.chunkIndexes.length,
    message_count: Number(statistics.messageCount),
    topics: {},
    messages: [],
  };
  for (const [id, ch] of channels) {
    const s = schemas.get(ch.schemaId);
    if (!s) fail(`channel ${ch.topic} has no schema`);
    JSON.parse(decoder.decode(s.data));  // the JSON Schema is JSON
    result.topics[ch.topic] = {
      encoding: ch.messageEncoding,
      schema: s.name,
      schema_encoding: s.encoding,
      metadata: Object.fromEntries(ch.metadata),
      count: Number(statistics.channelMessageCounts.get(id) ?? 0n),
    };
  }
  for (const m of messages) {
    const ch = channels.get(m.channelId);
    if (ch.messageEncoding !== "json") fail(`${ch.topic}: encoding ${ch.messageEncoding}`);
    result.messages.push({
      topic: ch.topic,
      sequence: m.sequence,
      log_time_ns: m.logTime.toString(),
      publish_time_ns: m.publishTime.toString(),
      data: JSON.parse(decoder.decode(m.data)),
    });
  }
  fs.writeFileSync(out, JSON.stringify(result));
  console.log(`mcap_read: ${messages.length} messages on ${channels.size} topics in ${indexed.chunkIndexes.length} chunks; ` +
              `indexed == streamed; data, summary and chunk CRCs correct`);
}

main().catch((e) => fail(e.stack || String(e)));
