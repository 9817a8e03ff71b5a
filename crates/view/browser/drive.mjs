// Drives glint view in Debian's headless Chromium through playwright-core (no browser
// download: the executable is /usr/bin/chromium or $CHROMIUM).
//
//   node drive.mjs test URL SCREENSHOT.png [FOREIGN_URL]
//                                            load, wait for the first frame, drag,
//                                            check the canvas changed, screenshot;
//                                            then the page at FOREIGN_URL (another
//                                            origin) opens the viewer's socket with
//                                            the URL's token: it must be refused
//   node drive.mjs progressive URL           a `path` scene: with the mouse still the
//                                            frames' sample count grows; a drag
//                                            restarts it at one sample, then it grows
//                                            again
//   node drive.mjs labels URL [SHOT.png]     a scene with a label map: the legend lists
//                                            the labels; unticking the first changes
//                                            the canvas, "all" brings the first back
//   node drive.mjs levels URL                an OME-Zarr pyramid shown coarse first:
//                                            the first frame's level and status, then
//                                            a frame of the finer level and its status
//   node drive.mjs bench URL SECONDS         drag for SECONDS; frames/s received
//                                            during the drag, input-to-frame latency
//
// Prints one JSON line; exits non-zero on failure.
import { chromium } from "playwright-core";

const [mode, url, arg, foreignUrl] = process.argv.slice(2);
if (!["test", "bench", "progressive", "labels", "levels"].includes(mode) || !url) {
  console.error("usage: drive.mjs test URL OUT.png [FOREIGN_URL] | drive.mjs progressive URL | drive.mjs labels URL [SHOT.png] | drive.mjs levels URL | drive.mjs bench URL SECONDS");
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  // As root in a closed network: no sandbox, no GPU, no background connections.
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
try {
  const page = await browser.newPage({ viewport: { width: 900, height: 640 } });
  page.on("pageerror", (e) => { console.error(`page error: ${e.message}`); process.exitCode = 1; });
  await page.goto(url);
  await page.waitForFunction(() => window.glint && window.glint.full >= 1, null, { timeout: 120000 });
  if (process.env.GLINT_VIEW) {
    // Start from a named view (the benchmark's scene).
    await page.click(`#views button:text-is("${process.env.GLINT_VIEW}")`);
    const full = await page.evaluate(() => window.glint.full);
    await page.waitForFunction((n) => window.glint.full > n, full, { timeout: 120000 });
  }
  const box = await page.locator("#frame").boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  const pixels = () => page.evaluate(() => document.getElementById("frame").toDataURL());
  // Waits for the full frame after `act` and returns the canvas.
  const afterFrame = async (act) => {
    const full = await page.evaluate(() => window.glint.full);
    await act();
    await page.waitForFunction((n) => window.glint.full > n, full, { timeout: 120000 });
    return pixels();
  };
  if (mode === "levels") {
    // Each frame's level and the status shown with it.
    const first = await page.evaluate(() => window.glint.frameLevels[0]);
    await page.waitForFunction(() => window.glint.level && !window.glint.level.coarse && window.glint.frameLevels.at(-1).level === window.glint.level.level, null, { timeout: 120000 });
    const later = await page.evaluate(() => window.glint.frameLevels.at(-1));
    const errors = await page.evaluate(() => window.glint.errors);
    console.log(JSON.stringify({ first, later, errors }));
    if (errors.length) process.exitCode = 1;
  } else if (mode === "labels") {
    const rows = await page.locator("#labels label").allTextContents();
    const visible = await page.locator("#labels-box").isVisible();
    const before = await pixels();
    // Click to full frame, ms (reported, not checked: the label layer is rebuilt).
    let t = Date.now();
    const hidden = await afterFrame(() => page.locator("#labels input").first().uncheck());
    const hideMs = Date.now() - t;
    t = Date.now();
    const all = await afterFrame(() => page.click("#labels-all"));
    const allMs = Date.now() - t;
    if (arg) await page.screenshot({ path: arg });
    const errors = await page.evaluate(() => window.glint.errors);
    const report = { rows: rows.length <= 8 ? rows : rows.length, visible, changed: hidden !== before, restored: all === before, hide_ms: hideMs, all_ms: allMs, errors };
    console.log(JSON.stringify(report));
    if (!visible || !report.changed || !report.restored || errors.length) process.exitCode = 1;
  } else if (mode === "progressive") {
    const g = () => page.evaluate(() => ({ samples: window.glint.samples, log: window.glint.sampleLog.slice(), errors: window.glint.errors }));
    const first = (await g()).samples;
    // Mouse still: refined frames arrive with more samples.
    await page.waitForFunction((n) => window.glint.samples > n && window.glint.samples >= 4, first, { timeout: 120000 });
    const grown = (await g()).samples;
    const mark = (await g()).log.length;
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    for (let i = 1; i <= 10; i++) await page.mouse.move(cx + 8 * i, cy + 2 * i);
    await page.mouse.up();
    // The drag's frames restart at one sample; then the count grows again.
    await page.waitForFunction((m) => window.glint.sampleLog.slice(m).includes(1), mark, { timeout: 120000 });
    await page.waitForFunction((m) => window.glint.sampleLog.slice(m).some((x, i, a) => i > 0 && a[i - 1] === 1 && x > 1), mark, { timeout: 120000 });
    const end = await g();
    const after = end.log.slice(mark);
    const restarted = after.includes(1);
    const regrown = Math.max(...after.slice(after.lastIndexOf(1)));
    const text = await page.evaluate(() => document.getElementById("samples").textContent);
    // Issue 42: an environment map chosen in the panel, then turned by an Alt-drag
    // (the camera stays where it was). Shift works in the page too, but headless
    // Chromium sends no pointerdown for a Shift-press from Playwright.
    const lit = await pixels();
    // A frame counted after the change may be a refinement of the scene before it:
    // the canvas is read once the served scene (sent after its frame) shows the change.
    await page.selectOption("#envmap", "studio");
    await page.waitForFunction(() => window.glint.scene.lighting.environment_map === "studio", null, { timeout: 30000 });
    const mapped = await pixels();
    const azimuth = await page.evaluate(() => window.glint.scene.camera.azimuth);
    await page.keyboard.down("Alt");
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    for (let i = 1; i <= 5; i++) await page.mouse.move(cx + 10 * i, cy);
    await page.mouse.up();
    await page.keyboard.up("Alt");
    const turn = await page.evaluate(() => Number(document.getElementById("env-rot").value));
    await page.waitForFunction((t) => window.glint.scene.lighting.environment_rotation === t, turn, { timeout: 30000 }).catch(() => {});
    const env = await page.evaluate(() => ({ map: window.glint.scene.lighting.environment_map, rotation: window.glint.scene.lighting.environment_rotation, azimuth: window.glint.scene.camera.azimuth, errors: window.glint.errors }));
    env.turn = turn;
    const envOk = mapped !== lit && env.map === "studio" && turn === 25 && env.rotation === 25 && env.azimuth === azimuth && !env.errors.length;
    // The area key light: on (a sphere where the light sliders point), then off again.
    await page.selectOption("#area-key", "sphere");
    await page.waitForFunction(() => (window.glint.scene.lighting.area_lights || []).length === 1, null, { timeout: 30000 }).catch(() => {});
    const keyed = await pixels();
    const key = await page.evaluate(() => (window.glint.scene.lighting.area_lights || [])[0] || null);
    await page.selectOption("#area-key", "");
    await page.waitForFunction(() => !window.glint.scene.lighting.area_lights, null, { timeout: 30000 }).catch(() => {});
    const unkeyed = await pixels();
    const keyOff = await page.evaluate(() => window.glint.scene.lighting.area_lights === undefined && !window.glint.errors.length);
    env.key = key;
    env.keyChanged = keyed !== unkeyed;
    const keyOk = env.keyChanged && key !== null && key.frame === "camera" && key.shape.sphere.radius === 40 && Math.abs(key.position[2] - 300) < 1e-6 && keyOff;
    env.keyOk = keyOk;
    console.log(JSON.stringify({ first, grown, restarted, regrown, text, after, errors: end.errors, env, envOk }));
    if (!(grown > first) || !restarted || !(regrown > 1) || end.errors.length || !envOk || !keyOk) process.exitCode = 1;
  } else if (mode === "test") {
    const before = await pixels();
    const full = await page.evaluate(() => window.glint.full);
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    for (let i = 1; i <= 10; i++) await page.mouse.move(cx + 8 * i, cy + 2 * i);
    await page.mouse.up();
    await page.waitForFunction((n) => window.glint.full > n, full, { timeout: 120000 });
    const after = await pixels();
    await page.screenshot({ path: arg });
    const g = await page.evaluate(() => ({ frames: window.glint.frames, full: window.glint.full, errors: window.glint.errors }));
    const changed = before !== after;
    const foreign = foreignUrl ? await foreignSocket(url, foreignUrl) : "not tried";
    console.log(JSON.stringify({ ...g, changed, foreign }));
    if (!changed || g.errors.length || (foreignUrl && foreign !== "refused")) process.exitCode = 1;
  } else {
    const seconds = Number(arg || 5);
    await page.evaluate(() => { window.glint.latencies.length = 0; if (window.glint.dragLog) window.glint.dragLog.length = 0; });
    const f0 = await page.evaluate(() => window.glint.frames);
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    const t0 = Date.now();
    let i = 0;
    // A steady drag: one pointer move every 16 ms (a 60 Hz mouse), in a circle.
    while (Date.now() - t0 < seconds * 1000) {
      i += 1;
      await page.mouse.move(cx + 80 * Math.cos(i / 20), cy + 40 * Math.sin(i / 20));
      await new Promise((r) => setTimeout(r, 16));
    }
    const elapsed = (Date.now() - t0) / 1000;
    const f1 = await page.evaluate(() => window.glint.frames);
    await page.mouse.up();
    const lat = (await page.evaluate(() => window.glint.latencies.slice())).sort((a, b) => a - b);
    const q = (p) => lat.length ? lat[Math.min(lat.length - 1, Math.floor(p * lat.length))] : NaN;
    // The drag frames: how many were path-traced, their sizes (long side) and render times.
    // (A page older than the log has none: then no drag frame is counted.)
    const drag = await page.evaluate(() => (window.glint.dragLog || []).slice());
    const path = drag.filter((d) => d[2] > 0);
    const sides = path.map((d) => Math.max(d[0], d[1])).sort((a, b) => a - b);
    const ms = drag.map((d) => d[3]).sort((a, b) => a - b);
    const pathMs = path.map((d) => d[3]).sort((a, b) => a - b);
    const localMs = drag.filter((d) => d[2] === 0).map((d) => d[3]).sort((a, b) => a - b);
    const mid = (a) => a.length ? a[Math.floor(a.length / 2)] : null;
    console.log(JSON.stringify({ seconds: elapsed, events: i, frames: f1 - f0,
      fps: (f1 - f0) / elapsed, latency_ms_p50: q(0.5), latency_ms_p95: q(0.95), samples: lat.length,
      drag_frames: drag.length, path_frames: path.length,
      path_side_min: sides[0] ?? null, path_side_median: mid(sides), path_side_max: sides[sides.length - 1] ?? null,
      render_ms_median: mid(ms), path_render_ms_median: mid(pathMs), local_render_ms_median: mid(localMs) }));
  }
} finally {
  await browser.close();
}

// The page at foreignUrl (another server: another origin) opens the viewer's socket
// with the viewer's own query (its token): "opened", "refused" or "timeout".
async function foreignSocket(viewerUrl, foreignUrl) {
  const socket = new URL(viewerUrl);
  socket.protocol = "ws:";
  socket.pathname = "/ws";
  const page = await browser.newPage();
  await page.goto(foreignUrl);
  return page.evaluate((u) => new Promise((resolve) => {
    const s = new WebSocket(u);
    s.onopen = () => { s.close(); resolve("opened"); };
    s.onerror = () => resolve("refused");
    setTimeout(() => resolve("timeout"), 20000);
  }), socket.href);
}
