// glint view: draws the frames the server renders and sends interaction as partial
// scenes. window.glint exposes counters for the browser test and the benchmark.
"use strict";
const $ = (id) => document.getElementById(id);
const canvas = $("frame");
const ctx = canvas.getContext("2d");
const glint = (window.glint = { level: null, frameLevels: [], frames: 0, full: 0, samples: 0, sampleLog: [], dragLog: [], latencies: [], errors: [], sent: new Map(), scene: null, saved: null });
// Scripts beside this one (pick.js) see every text message and send their own.
glint.hooks = { message: [], binary: [] };
let seq = 0;
let scene = null;
// The pyramid level of an OME-Zarr store the frames come from ("" otherwise).
let levelText = "";
const frameTimes = [];

// A viewer on a non-loopback address needs its token (the printed URL's ?token=...):
// the page passes it on to its own socket, the only other request that needs it.
const token = new URLSearchParams(location.search).get("token");
const query = token === null ? "" : `?token=${encodeURIComponent(token)}`;
const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws${query}`);
ws.binaryType = "arraybuffer";

function send(msg) {
  if (ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(msg));
}
glint.send = send;

// Sends a partial scene; interactive updates get a quick half-size frame.
function update(patch, interactive = false) {
  seq += 1;
  glint.sent.set(seq, performance.now());
  send({ type: "update", seq, interactive, scene: patch });
}
glint.update = update;

function fill(select, names) {
  select.innerHTML = "";
  for (const n of names) select.add(new Option(n, n));
}

// Messages are handled one after another, in the order they came: a frame's image is
// decoded asynchronously, and a message after it (a level change) must not overtake it.
let handled = Promise.resolve();
ws.onmessage = (ev) => { handled = handled.then(() => handle(ev)).catch((e) => glint.errors.push(String(e))); };

async function handle(ev) {
  if (typeof ev.data === "string") {
    const msg = JSON.parse(ev.data);
    for (const hook of glint.hooks.message) hook(msg);
    if (msg.type === "hello") {
      scene = msg.scene;
      fill($("preset"), msg.presets);
      fill($("lobe"), msg.lobes);
      for (const m of msg.environments || []) $("envmap").add(new Option(m, m));
      const views = $("views");
      for (const v of msg.views) {
        const b = document.createElement("button");
        b.type = "button";
        b.textContent = v;
        b.onclick = () => { scene.camera = { ...scene.camera, view: v, azimuth: 0, elevation: 0 }; update({ camera: { view: v, azimuth: 0, elevation: 0 } }); };
        views.append(b);
      }
      showLabels(msg.labels || []);
      showLevel(msg.level);
      $("iso").min = msg.range[0];
      $("iso").max = msg.range[1];
      showScene(scene);
    } else if (msg.type === "level") {
      showLevel(msg.level);
    } else if (msg.type === "scene") {
      glint.scene = msg.scene;
      if (glint.saving) { download("scene.json", new Blob([JSON.stringify(msg.scene, null, 2)], { type: "application/json" })); glint.saving = false; }
    } else if (msg.type === "error") {
      glint.errors.push(msg.message);
      $("error").textContent = msg.message;
    }
    return;
  }
  // A binary message another script expects (record.js's file) is its own.
  if (glint.hooks.binary.some((hook) => hook(ev.data))) return;
  const view = new DataView(ev.data);
  const magic = String.fromCharCode(...new Uint8Array(ev.data, 0, 4));
  if (magic !== "GLNT") return;
  const h = { seq: view.getUint32(4, true), width: view.getUint32(8, true), height: view.getUint32(12, true),
    ms: view.getFloat32(16, true), format: view.getUint8(20), purpose: view.getUint8(21),
    samples: view.getUint16(22, true) };
  const blob = new Blob([new Uint8Array(ev.data, 24)], { type: h.format === 0 ? "image/jpeg" : "image/png" });
  if (h.purpose === 2) { download("glint.png", blob); return; }
  const bitmap = await createImageBitmap(blob);
  if (h.purpose === 1) { canvas.width = h.width; canvas.height = h.height; }
  ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
  const now = performance.now();
  glint.frames += 1;
  if (h.purpose === 1) glint.full += 1;
  // Path-traced frames: the samples per pixel they hold (refined while the scene holds still).
  glint.samples = h.samples;
  glint.sampleLog.push(h.samples);
  // Drag frames: their size, samples (path-traced: 1; local: 0) and render time, for
  // the benchmark (the last 4096).
  if (h.purpose === 0) glint.dragLog.push([h.width, h.height, h.samples, h.ms]);
  if (glint.dragLog.length > 4096) glint.dragLog.shift();
  $("samples").textContent = h.samples > 0 ? `${h.samples} samples per pixel` : "";
  // Input-to-frame latency: every event this frame reflects (its seq and the older
  // ones, merged into it on the server) waited from its pointer event until now.
  for (const [s, t] of glint.sent) {
    if (s <= h.seq) { glint.latencies.push(now - t); glint.sent.delete(s); }
  }
  frameTimes.push(now);
  while (frameTimes.length && now - frameTimes[0] > 1000) frameTimes.shift();
  $("timing").textContent = `${h.width}×${h.height} in ${h.ms.toFixed(1)} ms · ${frameTimes.length} frames/s`;
  $("status").textContent = [h.purpose === 0 ? "interactive" : "", levelText].filter((t) => t).join(" · ");
  glint.frameLevels.push({ level: glint.level ? glint.level.level : null, status: $("status").textContent });
  $("error").textContent = "";
};
ws.onclose = () => { $("status").textContent = "disconnected"; };

function showScene(s) {
  $("preset").value = s.preset || "";
  $("mode").value = s.mode;
  $("lobe").value = s.lobe.kind;
  $("n").value = s.lobe.n;
  $("v").value = s.lobe.v;
  $("geometry").value = s.lobe.geometry;
  $("projection").value = s.camera.projection;
  if (s.iso !== undefined) $("iso").value = s.iso;
  const l = s.lighting || { model: "local" };
  $("lighting").value = l.model;
  if (l.spp !== undefined) $("spp").value = l.spp;
  $("exposure").value = s.exposure || 0;
  $("tone").value = s.tone || "linear";
  $("aperture").value = s.camera.aperture || 0;
  $("focus").value = s.camera.focus === undefined ? "auto" : s.camera.focus;
  if (l.model === "path") $("denoise").checked = (l.denoise || "none") !== "none";
  const key = (l.area_lights || [])[0];
  $("area-key").value = key ? Object.keys(key.shape)[0] : "";
  if (key) $("area-radiance").value = key.radiance[1];
  $("envmap").value = l.environment_map || "";
  $("env-rot").value = l.environment_rotation || 0;
}

// The legend of the label map: a checkbox per label present (colour, name, voxel
// count); a change sends the labels not ticked as the scene's labels.hide list.
function showLabels(labels) {
  glint.labels = labels;
  const box = $("labels");
  box.innerHTML = "";
  $("labels-box").hidden = labels.length === 0;
  for (const l of labels) {
    const row = document.createElement("label");
    const tick = document.createElement("input");
    tick.type = "checkbox";
    tick.checked = l.shown;
    tick.dataset.value = String(l.value);
    tick.onchange = sendLabels;
    const swatch = document.createElement("span");
    swatch.className = "swatch";
    swatch.style.background = l.color;
    const name = document.createElement("span");
    name.textContent = l.name;
    const voxels = document.createElement("span");
    voxels.className = "voxels";
    voxels.textContent = l.voxels.toLocaleString("en");
    row.title = `label ${l.value}`;
    row.append(tick, swatch, name, voxels);
    box.append(row);
  }
}

function sendLabels() {
  const hide = [...$("labels").querySelectorAll("input")].filter((t) => !t.checked).map((t) => t.dataset.value);
  update({ labels: { show: null, hide } });
}

function tickAll(on) {
  for (const t of $("labels").querySelectorAll("input")) t.checked = on;
  sendLabels();
}

// A pyramid's level: "level 4 of 0–4 (4×3×10), loading a finer one" while coarse.
function showLevel(level) {
  glint.level = level || null;
  if (!level) { levelText = ""; return; }
  levelText = `level ${level.level} of 0–${level.levels - 1} (${level.dims.join("×")})${level.coarse ? ", loading a finer one" : ""}`;
  $("status").textContent = levelText;
}

function download(name, blob) {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}

// Dragging orbits the camera; the wheel zooms.
let drag = null;
canvas.addEventListener("pointerdown", (e) => { drag = { x: e.clientX, y: e.clientY }; canvas.setPointerCapture(e.pointerId); });
canvas.addEventListener("pointermove", (e) => {
  if (!drag || !scene) return;
  const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  drag = { x: e.clientX, y: e.clientY };
  // Alt- or Shift-drag turns the environment map (path lighting with a map), not the camera.
  if ((e.shiftKey || e.altKey) && $("envmap").value !== "" && $("lighting").value !== "local") {
    const turn = Math.round(((Number($("env-rot").value) + dx * 0.5 + 540) % 360) - 180);
    $("env-rot").value = turn;
    update({ lighting: { environment_rotation: turn } }, true);
    return;
  }
  const c = scene.camera;
  c.azimuth = (((c.azimuth - dx * 0.5) % 360) + 360) % 360;
  c.elevation = Math.max(-89, Math.min(89, c.elevation + dy * 0.5));
  update({ camera: { azimuth: c.azimuth, elevation: c.elevation } }, true);
});
canvas.addEventListener("pointerup", () => { drag = null; update({}, false); });
canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  if (!scene) return;
  scene.camera.zoom = Math.max(0.2, Math.min(20, scene.camera.zoom * Math.pow(1.1, -e.deltaY / 100)));
  update({ camera: { zoom: scene.camera.zoom } }, true);
}, { passive: false });

// The server applies the scene-editing rules (a preset replaces the transfer function,
// a mode without an isosurface forgets the iso value): Scene::patch.
$("preset").onchange = (e) => update({ preset: e.target.value });
$("mode").onchange = (e) => {
  const mode = e.target.value;
  const patch = mode === "iso" ? { mode, iso: Number($("iso").value) } : { mode };
  update(patch);
};
$("iso").oninput = (e) => { if ($("mode").value === "iso") update({ iso: Number(e.target.value) }, true); };
$("lobe").onchange = (e) => update({ lobe: { kind: e.target.value } });
$("n").onchange = (e) => update({ lobe: { n: Number(e.target.value) } });
$("v").onchange = (e) => update({ lobe: { v: Number(e.target.value) } });
$("geometry").onchange = (e) => update({ lobe: { geometry: e.target.value } });
$("projection").onchange = (e) => update({ camera: { projection: e.target.value } });
$("split").onchange = (e) => send({ type: "split", split: e.target.value });
// The area key light (lighting.area_lights, camera frame): 300 mm from the volume's
// centre towards Azimuth (the image's right) and Elevation (its top); while it is on,
// the two sliders move it instead of the directional light.
const KEY_DISTANCE = 300;
const areaKey = (interactive) => {
  const kind = $("area-key").value;
  if (kind === "") return update({ lighting: { area_lights: [] } }, interactive);
  const az = Number($("light-az").value) * Math.PI / 180, el = Number($("light-el").value) * Math.PI / 180;
  const size = Number($("area-size").value), radiance = Number($("area-radiance").value);
  const position = [Math.sin(az) * Math.cos(el), Math.sin(el), Math.cos(az) * Math.cos(el)].map((c) => KEY_DISTANCE * c);
  const shape = kind === "sphere" ? { sphere: { radius: size } } : { rect: { size: [size, Math.round(size * 2 / 3)] } };
  update({ lighting: { area_lights: [{ shape, frame: "camera", position, radiance: [radiance, radiance, radiance] }] } }, interactive);
};
const light = () => {
  if ($("area-key").value !== "") return areaKey(true);
  update({ lights: [{ azimuth: Number($("light-az").value), elevation: Number($("light-el").value), intensity: 1 }] }, true);
};
$("light-az").oninput = light;
$("light-el").oninput = light;
$("area-key").onchange = () => areaKey(false);
$("area-size").onchange = () => areaKey(false);
$("area-radiance").onchange = () => areaKey(false);
// The lighting model: only the settings the model uses are sent (the others are
// refused by the scene), the sample count with `path`.
$("lighting").onchange = (e) => {
  const model = e.target.value;
  const patch = { model, spp: null, bounces: null, seed: null, environment: null, anisotropy: null, occlusion: null, sampler: null, time_budget: null, show_environment: null, denoise: null };
  if (model === "path") {
    patch.spp = Number($("spp").value);
    // Denoised by default (the toggle starts on): OIDN in builds with it, else à-trous.
    patch.denoise = $("denoise").checked ? "auto" : "none";
  }
  if (model !== "local" && $("envmap").value !== "") Object.assign(patch, environment());
  else Object.assign(patch, { environment_map: null, environment_rotation: null });
  update({ lighting: patch });
};
$("denoise").onchange = (e) => {
  if ($("lighting").value === "path") update({ lighting: { denoise: e.target.checked ? "auto" : "none" } });
};
// The environment: a map replaces the uniform one (the scene refuses both, and a
// map's rotation without a map); path lighting, and shadows (the map as a few fitted
// directional lights).
const environment = () => {
  const map = $("envmap").value;
  return map === ""
    ? { environment_map: null, environment_rotation: null }
    : { environment: null, environment_map: map, environment_rotation: Number($("env-rot").value) };
};
$("envmap").onchange = () => { if ($("lighting").value !== "local") update({ lighting: environment() }); };
$("env-rot").oninput = (e) => {
  if ($("lighting").value !== "local" && $("envmap").value !== "") update({ lighting: { environment_rotation: Number(e.target.value) } }, true);
};
$("spp").onchange = (e) => { if ($("lighting").value === "path") update({ lighting: { spp: Number(e.target.value) } }); };
// Film: the exposure and tone curve map the radiance for display (a path image keeps
// its samples); the thin lens (path lighting) focuses at a distance in mm or "auto".
$("exposure").oninput = (e) => update({ exposure: Number(e.target.value) }, true);
$("exposure").onchange = (e) => update({ exposure: Number(e.target.value) });
$("tone").onchange = (e) => update({ tone: e.target.value });
$("aperture").onchange = (e) => update({ camera: { aperture: Number(e.target.value) } });
$("focus").onchange = (e) => {
  const v = e.target.value.trim().toLowerCase();
  update({ camera: { focus: v === "" || v === "auto" ? "auto" : Number(v) } });
};
$("save").onclick = () => { glint.saving = true; send({ type: "save" }); };
$("labels-all").onclick = () => tickAll(true);
$("labels-none").onclick = () => tickAll(false);
