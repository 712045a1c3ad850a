// The page: opens WebGPU through rae-web (pkg/, made by wasm-bindgen), denoises the shipped
// sample or the user's own per-buffer sequence frame by frame with the hidden state carried,
// and shows noisy | denoised | reference with each frame's time and error.
//
// `?default-limits` asks the GPU for WebGPU's default limits only (what scripts/web-test.sh
// runs with); window.raeTest() is the test's entry point.
import init, { Session, Frame, frameNumber } from "./pkg/rae_web.js";

const params = new URLSearchParams(location.search);
const $ = (id) => document.getElementById(id);
let session = null;
let manifest = null;
let busy = false;
/** The model loaded into the session: its manifest entry and the buffers it reads. */
let loaded = null;
const modelBytes = new Map();

function message(text) {
  $("message").textContent = text || "";
  $("message").hidden = !text;
}

function status(text) {
  $("status").textContent = text;
}

function errorText(e) {
  return String(e && e.message ? e.message : e);
}

async function fetchBytes(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: ${r.status} ${r.statusText}`);
  return new Uint8Array(await r.arrayBuffer());
}

async function start() {
  if (!navigator.gpu) {
    message("This browser has no WebGPU (navigator.gpu is missing), and rae runs on WebGPU: " +
      "use a browser that has it (Chrome or Edge 113 and later, Safari 26, Firefox 141 on Windows).");
    $("adapter").textContent = "No WebGPU.";
    return;
  }
  await init();
  try {
    session = await Session.open(params.has("default-limits"));
  } catch (e) {
    message(errorText(e));
    $("adapter").textContent = "No GPU.";
    return;
  }
  if (params.get("tile")) session.setTile(params.get("tile"));
  $("adapter").textContent = "GPU: " + session.adapter();
  manifest = await (await fetch("manifest.json")).json();
  for (const m of manifest.models) {
    const o = document.createElement("option");
    o.value = m.name;
    o.textContent = m.name;
    $("model").append(o);
  }
  $("run-sample").disabled = false;
  $("pick").disabled = false;
  $("run-sample").onclick = () => runSample().catch((e) => message(errorText(e)));
  $("pick").onchange = (ev) => runPicked(ev.target.files).catch((e) => message(errorText(e)));
  document.body.dataset.ready = "1";
}

/** Load a model into the session unless it is loaded; returns the buffers it reads. */
async function loadModel(entry) {
  if (loaded && loaded.entry.name === entry.name) return loaded.buffers;
  if (!modelBytes.has(entry.name)) modelBytes.set(entry.name, await fetchBytes(entry.file));
  const buffers = session.loadWeights(entry.file, modelBytes.get(entry.name));
  loaded = { entry, buffers };
  return buffers;
}

/** The chosen model, or the first shipped one whose buffers the frame has (as rae-cli picks). */
async function chooseModel(frameBuffers) {
  const choice = $("model").value;
  if (choice !== "auto") {
    const entry = manifest.models.find((m) => m.name === choice);
    const needs = await loadModel(entry);
    const missing = needs.filter((b) => !frameBuffers.includes(b));
    if (missing.length) throw new Error(`${entry.name} reads ${needs.join(", ")}; the sequence has no ${missing.join(", ")}`);
    return entry.name;
  }
  for (const entry of manifest.models) {
    const needs = await loadModel(entry);
    if (needs.every((b) => frameBuffers.includes(b))) return entry.name;
  }
  throw new Error(`no shipped model reads only the sequence's buffers (${frameBuffers.join(", ")})`);
}

/**
 * Group files ({name, load}) into frames by the number in their names; every frame must have
 * the first frame's buffers, and the numbers must follow each other.
 */
function groupFrames(files) {
  const frames = new Map();
  for (const f of files) {
    const n = frameNumber(f.name);
    if (n === undefined) {
      throw new Error(`${f.name}: not a per-buffer file (color_0001.exr, albedo_, normal_, depth_, roughness_, motion_, reference_)`);
    }
    if (!frames.has(n)) frames.set(n, []);
    frames.get(n).push(f);
  }
  if (frames.size === 0) throw new Error("no files picked");
  const numbers = [...frames.keys()].sort((a, b) => a - b);
  const prefix = (name) => name.replace(/[-_.]?\d+\.[^.]+$/, "").toLowerCase();
  const first = frames.get(numbers[0]).map((f) => prefix(f.name)).sort().join(",");
  numbers.forEach((n, i) => {
    if (i > 0 && n !== numbers[i - 1] + 1) throw new Error(`frame ${numbers[i - 1] + 1} is missing (frames ${numbers[0]} to ${numbers.at(-1)})`);
    const these = frames.get(n).map((f) => prefix(f.name)).sort().join(",");
    if (these !== first) throw new Error(`frame ${n} has ${these}, frame ${numbers[0]} has ${first}: every frame needs the same buffers`);
  });
  return numbers.map((n) => ({ number: n, files: frames.get(n) }));
}

function draw(canvasId, width, height, rgba) {
  const c = $(canvasId);
  c.width = width;
  c.height = height;
  c.getContext("2d").putImageData(new ImageData(new Uint8ClampedArray(rgba), width, height), 0, 0);
}

function clear(canvasId) {
  const c = $(canvasId);
  c.getContext("2d").clearRect(0, 0, c.width, c.height);
}

const fmt = (v, digits) => (Number.isFinite(v) ? v.toFixed(digits) : "-");

function median(values) {
  const s = [...values].sort((a, b) => a - b);
  return s.length ? s[Math.floor(s.length / 2)] : NaN;
}

/**
 * Denoise frames in order with the hidden state carried (reset first). Returns per frame its
 * number, ms, errors and, with keepOutputs, its output.
 */
async function denoiseSequence(label, frames, keepOutputs = false) {
  if (busy) throw new Error("a sequence is being denoised");
  busy = true;
  $("run-sample").disabled = true;
  message("");
  const body = $("frames").tBodies[0];
  body.replaceChildren();
  const results = [];
  try {
    session.reset();
    let model = null;
    for (const f of frames) {
      const frame = new Frame();
      try {
        for (const file of f.files) frame.add(file.name, await file.load());
        if (model === null) model = await chooseModel(frame.buffers());
        status(`${label}: frame ${f.number} (${frame.width()}x${frame.height()}, ${model})...`);
        const t0 = performance.now();
        const out = await session.denoise(frame);
        const ms = performance.now() - t0;
        const e = out.errors(frame);
        draw("noisy", frame.width(), frame.height(), frame.rgba("color"));
        draw("denoised", out.width(), out.height(), out.rgba());
        if (frame.hasReference()) draw("reference", frame.width(), frame.height(), frame.rgba("reference"));
        else clear("reference");
        const row = body.insertRow();
        const cells = [f.number, fmt(ms, 1)];
        if (e) cells.push(fmt(e.psnrIn, 2), fmt(e.psnrOut, 2), fmt(e.relmseIn, 4), fmt(e.relmseOut, 4), fmt(e.ssimOut, 4));
        else cells.push("-", "-", "-", "-", "-");
        for (const c of cells) row.insertCell().textContent = c;
        const result = { number: f.number, ms, psnrIn: e?.psnrIn, psnrOut: e?.psnrOut, relmseOut: e?.relmseOut };
        if (keepOutputs) result.output = out.output();
        results.push(result);
        e?.free();
        out.free();
      } finally {
        frame.free();
      }
      // Let the page paint between frames.
      await new Promise((r) => setTimeout(r, 0));
    }
    const later = results.slice(1).map((r) => r.ms);
    status(`${label}: ${results.length} frames with ${model}; ${fmt(results[0].ms, 1)} ms the first (builds the denoiser), ` +
      `median ${fmt(median(later.length ? later : [results[0].ms]), 1)} ms a frame after it (upload, GPU, readback).`);
    return results;
  } finally {
    busy = false;
    $("run-sample").disabled = false;
  }
}

async function runSample(keepOutputs = false) {
  const s = manifest.sample;
  const files = s.files.map((name) => ({ name, load: () => fetchBytes(`${s.path}/${name}`) }));
  return denoiseSequence(`sample ${s.name}`, groupFrames(files), keepOutputs);
}

async function runPicked(fileList) {
  const files = [...fileList].map((file) => ({ name: file.name, load: async () => new Uint8Array(await file.arrayBuffer()) }));
  return denoiseSequence(`${files.length} files`, groupFrames(files));
}

function base64(f32) {
  const u8 = new Uint8Array(f32.buffer, f32.byteOffset, f32.byteLength);
  let s = "";
  for (let i = 0; i < u8.length; i += 0x8000) s += String.fromCharCode.apply(null, u8.subarray(i, i + 0x8000));
  return btoa(s);
}

/**
 * The test's entry point (scripts/web-test.sh): every golden fixture in the manifest held to
 * PyTorch, then the sample denoised with its outputs returned (base64 little-endian f32).
 */
window.raeTest = async () => {
  const golden = [];
  for (const g of manifest.golden) {
    const r = await session.verifyGolden(g.file, await fetchBytes(g.file), await fetchBytes(g.weights));
    golden.push({ file: g.file, frames: r.frames, worst: r.worst, maxAbs: r.maxAbs });
    r.free();
  }
  const frames = await runSample(true);
  return {
    adapter: session.adapter(),
    golden,
    sample: frames.map((f) => ({ ...f, output: base64(f.output) })),
  };
};

start().catch((e) => message(errorText(e)));
