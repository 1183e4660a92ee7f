// Open MCAP files as Foxglove and Lichtblick do: parse every schema with Foxglove's ROS message-definition
// parser (@foxglove/rosmsg, ros2 mode) and decode every message with its CDR reader
// (@foxglove/rosmsg2-serialization). Every schema must be ros2msg and every message must decode.
//
//   node test/foxglove/check.mjs [--json] [--samples] FILE.mcap...
//
// Prints one line per file and a summary (with --json: one JSON object instead; --samples adds the first
// decoded message of each topic). Exit 0 when every file parsed and decoded, 1 otherwise, 2 on bad usage.
// Installed by scripts/setup.sh (npm ci in test/foxglove); run by test/test_foxglove_schemas.py.
import { readFile } from "node:fs/promises";
import { McapIndexedReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import { decompress as zstd } from "fzstd";
import lz4 from "lz4js";

const decompressHandlers = {
  zstd: (data, size) => zstd(data, new Uint8Array(Number(size))),
  lz4: (data) => Uint8Array.from(lz4.decompress(data)),
};

class BufReadable {
  constructor(buf) { this.buf = buf; }
  async size() { return BigInt(this.buf.byteLength); }
  async read(offset, length) {
    return new Uint8Array(this.buf.buffer, this.buf.byteOffset + Number(offset), Number(length));
  }
}

// Decoded messages as plain JSON: typed arrays -> arrays, bigint -> number.
function plain(x) {
  if (typeof x === "bigint") return Number(x);
  if (ArrayBuffer.isView(x)) return Array.from(x, plain);
  if (Array.isArray(x)) return x.map(plain);
  if (x && typeof x === "object") return Object.fromEntries(Object.entries(x).map(([k, v]) => [k, plain(v)]));
  return x;
}

async function checkFile(path, samples) {
  const out = { path, ok: false, error: null, schemas: [], messages: 0, topics: {} };
  if (samples) out.samples = {};
  try {
    const reader = await McapIndexedReader.Initialize({
      readable: new BufReadable(await readFile(path)), decompressHandlers });
    const readers = new Map();
    for (const [id, s] of reader.schemasById) {
      if (s.encoding !== "ros2msg") throw new Error(`schema ${s.name}: encoding ${s.encoding}, not ros2msg`);
      let defs;
      try {
        defs = parse(new TextDecoder().decode(s.data), { ros2: true });
      } catch (e) {
        throw new Error(`schema ${s.name}: ${String(e.message || e).split("\n")[0]}`);
      }
      readers.set(id, new MessageReader(defs));
      out.schemas.push(s.name);
    }
    for await (const m of reader.readMessages()) {
      const ch = reader.channelsById.get(m.channelId);
      const r = readers.get(ch.schemaId);
      if (!r) throw new Error(`topic ${ch.topic}: no schema`);
      if (ch.messageEncoding !== "cdr") throw new Error(`topic ${ch.topic}: encoding ${ch.messageEncoding}, not cdr`);
      let msg;
      try {
        msg = r.readMessage(m.data);
      } catch (e) {
        throw new Error(`topic ${ch.topic}, message at ${m.logTime} ns: ${String(e.message || e).split("\n")[0]}`);
      }
      out.messages++;
      out.topics[ch.topic] = (out.topics[ch.topic] || 0) + 1;
      if (samples && !(ch.topic in out.samples)) out.samples[ch.topic] = plain(msg);
    }
    out.ok = true;
  } catch (e) {
    out.error = String(e.message || e).split("\n")[0];
  }
  return out;
}

const args = process.argv.slice(2);
const json = args.includes("--json"), samples = args.includes("--samples");
const paths = args.filter((a) => !a.startsWith("--"));
const unknown = args.filter((a) => a.startsWith("--") && a !== "--json" && a !== "--samples");
if (unknown.length || !paths.length) {
  console.error("usage: node check.mjs [--json] [--samples] FILE.mcap...");
  process.exit(2);
}
const files = [];
for (const path of paths) {
  const r = await checkFile(path, samples);
  files.push(r);
  if (!json) {
    console.log(r.ok ? `ok ${path}: ${r.schemas.length} schemas, ${r.messages} messages decoded`
                     : `FAIL ${path}: ${r.error}`);
  }
}
const parsed = files.filter((f) => f.ok).length;
const messages = files.reduce((n, f) => n + f.messages, 0);
if (json) {
  console.log(JSON.stringify({ files, parsed, total: files.length, messages }));
} else {
  console.log(`foxglove: ${parsed}/${files.length} files parsed and decoded (${messages} messages)`);
}
process.exit(parsed === files.length ? 0 : 1);
