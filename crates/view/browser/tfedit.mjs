// Drives glint view's window/level drag and transfer-function editor in Debian's
// headless Chromium through playwright-core (as drive.mjs does), checking the frames.
//
//   node tfedit.mjs wl URL     a MIP scene (grey ramp): a shift-drag up raises the
//                              level (the frame darkens), a right-drag down lowers it
//                              (brighter than at first), a right-drag left narrows the
//                              window (more contrast); the camera does not turn
//   node tfedit.mjs edit URL   a scene with a two-point transfer function: a click on
//                              the editor adds an opaque point (the frame brightens),
//                              dragging it down makes it faint (darker again), a double
//                              click deletes it (the first frame, byte for byte)
//
// Prints one JSON line; exits non-zero on failure.
import { chromium } from "playwright-core";

const [mode, url] = process.argv.slice(2);
if (!["wl", "edit"].includes(mode) || !url) {
  console.error("usage: tfedit.mjs wl URL | tfedit.mjs edit URL");
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
const fail = [];
const report = { mode };
const check = (ok, what) => { if (!ok) fail.push(what); };
try {
  const page = await browser.newPage({ viewport: { width: 900, height: 700 } });
  page.on("pageerror", (e) => fail.push(`page error: ${e.message}`));
  await page.goto(url);
  await page.waitForFunction(() => window.glint && window.glint.full >= 1 && window.glintTf
    && window.glintTf.state.tf && window.glintTf.state.histogram, null, { timeout: 120000 });
  // The frame's mean and standard deviation of luma (0..255).
  const stats = () => page.evaluate(() => {
    const c = document.getElementById("frame");
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let s = 0, s2 = 0, n = 0;
    for (let i = 0; i < d.length; i += 4) {
      const y = 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
      s += y; s2 += y * y; n += 1;
    }
    const mean = s / n;
    return { mean, sd: Math.sqrt(Math.max(0, s2 / n - mean * mean)) };
  });
  const pixels = () => page.evaluate(() => document.getElementById("frame").toDataURL());
  // Runs `act`, then waits for the full frame and the scene of the last update.
  const settled = async (act) => {
    const [full, scenes] = await page.evaluate(() => [window.glint.full, window.glintTf.scenes || 0]);
    await act();
    await page.waitForFunction(([f, n]) => window.glint.full > f && (window.glintTf.scenes || 0) > n
      && window.glint.scene && window.glint.scene.derived, [full, scenes], { timeout: 120000 });
    // The scene message follows its frame; let the frame's bitmap land too.
    await page.waitForTimeout(50);
  };
  const wl = () => page.evaluate(() => ({ ...window.glintTf.state.wl, text: document.getElementById("wl").textContent }));
  const box = await page.locator("#frame").boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  const drag = async (dx, dy, button) => {
    await page.mouse.move(cx, cy);
    await page.mouse.down({ button });
    for (let i = 1; i <= 10; i++) await page.mouse.move(cx + (dx * i) / 10, cy + (dy * i) / 10);
    await page.mouse.up({ button });
  };
  report.histogram_bins = await page.evaluate(() => window.glintTf.state.histogram.log_counts.length);
  check(report.histogram_bins === 256, "the histogram has 256 bins");
  if (mode === "wl") {
    const camera = await page.evaluate(() => JSON.stringify(window.glint.scene ? window.glint.scene.camera : null));
    const s0 = await stats(), w0 = await wl();
    await settled(async () => {
      await page.keyboard.down("Shift");
      await drag(0, -40, "left");
      await page.keyboard.up("Shift");
    });
    const s1 = await stats(), w1 = await wl();
    await settled(() => drag(0, 80, "right"));
    const s2 = await stats(), w2 = await wl();
    await settled(() => drag(-120, 0, "right"));
    const s3 = await stats(), w3 = await wl();
    const server = await page.evaluate(() => window.glint.scene.window_level);
    const cameraAfter = await page.evaluate(() => JSON.stringify(window.glint.scene.camera));
    Object.assign(report, { means: [s0.mean, s1.mean, s2.mean, s3.mean], sds: [s0.sd, s2.sd, s3.sd],
      wl: [w0, w1, w2, w3], server, camera_kept: camera === cameraAfter });
    check(w1.level > w0.level && Math.abs(w1.window - w0.window) < 1e-9 * w0.window + 1e-12, "shift-drag up raises the level only");
    check(s1.mean < s0.mean - 1, "a higher level darkens the frame");
    check(w2.level < w0.level, "right-drag down lowers the level below the first");
    check(s2.mean > s0.mean + 1, "a lower level brightens the frame");
    check(w3.window < w2.window && w3.level === w2.level, "right-drag left narrows the window");
    check(s3.sd > s2.sd, "a narrower window raises the contrast");
    check(server && Math.abs(server.window - w3.window) < 1e-9 && Math.abs(server.level - w3.level) < 1e-9, "the server's scene holds the window");
    check(w3.text.startsWith("W ") && w3.text.includes(" L "), "the panel shows W and L");
    check(camera === cameraAfter, "window/level drags do not turn the camera");
  } else {
    const before = await pixels(), s0 = await stats();
    const n0 = await page.evaluate(() => window.glintTf.state.tf.opacity.length);
    const screen = (v, a) => page.evaluate(([v, a]) => window.glintTf.screen(v, a), [v, a]);
    // Add: an opaque point at the brain's value (0.2).
    let p = await screen(0.2, 1.0);
    await settled(() => page.mouse.click(p.x, p.y));
    const added = await page.evaluate(() => window.glintTf.state.tf.opacity.map((q) => q.slice()));
    const s1 = await stats();
    // Move: drag it down to a faint opacity.
    const q = await screen(0.2, 0.1);
    await settled(async () => {
      await page.mouse.move(p.x, p.y);
      await page.mouse.down();
      for (let i = 1; i <= 8; i++) await page.mouse.move(p.x, p.y + ((q.y - p.y) * i) / 8);
      await page.mouse.up();
    });
    const moved = await page.evaluate(() => window.glintTf.state.tf.opacity.map((r) => r.slice()));
    const s2 = await stats();
    // Delete: a double click on it.
    await settled(() => page.mouse.dblclick(q.x, q.y));
    const after = await pixels();
    const n3 = await page.evaluate(() => window.glintTf.state.tf.opacity.length);
    const server = await page.evaluate(() => window.glint.scene.transfer_function);
    Object.assign(report, { means: [s0.mean, s1.mean, s2.mean], points: [n0, added.length, moved.length, n3],
      added, moved, restored: before === after, server_points: server ? server.opacity.length : null });
    check(added.length === n0 + 1 && added.some(([v, a]) => Math.abs(v - 0.2) < 0.01 && a > 0.95), "a click adds an opaque point at 0.2");
    check(s1.mean > s0.mean + 1, "an opaque brain brightens the frame");
    check(moved.length === n0 + 1 && moved.some(([v, a]) => Math.abs(v - 0.2) < 0.01 && Math.abs(a - 0.1) < 0.03), "the drag moves the point to 0.1");
    check(s2.mean < s1.mean - 1, "a faint brain darkens the frame again");
    check(n3 === n0 && server && server.opacity.length === n0, "a double click deletes the point");
    check(before === after, "deleting the point restores the first frame");
  }
  report.errors = await page.evaluate(() => window.glint.errors);
  check(report.errors.length === 0, "no errors from the server");
} finally {
  await browser.close();
}
console.log(JSON.stringify({ ...report, fail }));
if (fail.length) process.exitCode = 1;
