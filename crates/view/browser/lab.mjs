// Drives glint.Viewer inside JupyterLab in Debian's headless Chromium (no browser
// download), for scripts/notebook-screenshot:
//
//   node lab.mjs URL SCREENSHOT.png     open the notebook at URL (JupyterLab started
//                                       with expose_app_in_browser, and its token), run
//                                       all cells, wait for the viewer's first frame,
//                                       drag on it, check the image changed, write a
//                                       screenshot of the widget (canvas and panel)
//
// Everything goes through JupyterLab's own objects (window.jupyterapp): the command
// "notebook:run-all-cells" rather than a click on a menu that may not have opened yet,
// and the cells' execution counts and the kernel's status rather than fixed pauses.
// The frame is read from the widget's <img> (drawn onto a canvas, pixel statistics),
// so a grey canvas (jupyter_rfb's placeholder, no frame arrived) fails.
//
// Prints one JSON line (the statistics and timings); exits non-zero on failure.
import { chromium } from "playwright-core";

const [url, shot] = process.argv.slice(2);
if (!url || !shot) {
  console.error("usage: lab.mjs URL SCREENSHOT.png");
  process.exit(2);
}
// A frame: an image larger than the placeholder pixel whose pixels vary.
const MIN_STD = 8;
// The mean absolute difference (0-255) a drag must make.
const MIN_DIFF = 2;

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
const t0 = Date.now();
const secs = () => +((Date.now() - t0) / 1000).toFixed(1);
const result = { ok: false };
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  await page.goto(url);
  // The notebook open, its kernel started and idle.
  await page.waitForFunction(() => {
    const app = window.jupyterapp;
    const panel = app && app.shell.currentWidget;
    const kernel = panel && panel.sessionContext && panel.sessionContext.session &&
      panel.sessionContext.session.kernel;
    return kernel && kernel.connectionStatus === "connected" && kernel.status === "idle" &&
      panel.content && panel.content.widgets.length > 0;
  }, null, { timeout: 120000, polling: 250 });
  result.kernel_s = secs();
  await page.evaluate(() => window.jupyterapp.commands.execute("notebook:run-all-cells"));
  // Every code cell ran (an execution count) and the kernel is idle again.
  await page.waitForFunction(() => {
    const panel = window.jupyterapp.shell.currentWidget;
    const cells = panel.content.widgets.filter((c) => c.model.type === "code");
    return cells.every((c) => c.model.executionCount) &&
      panel.sessionContext.session.kernel.status === "idle";
  }, null, { timeout: 300000, polling: 250 });
  result.ran_s = secs();
  const img = page.locator("img.renderview-view").first();
  await img.waitFor({ timeout: 60000 });
  await img.scrollIntoViewIfNeeded();
  // Pixel statistics of the frame the <img> shows now (its pixels kept in the page as
  // window.__glint[tag], for the difference below).
  const stats = (tag) => img.evaluate((e, tag) => {
    const c = document.createElement("canvas");
    c.width = e.naturalWidth;
    c.height = e.naturalHeight;
    const ctx = c.getContext("2d");
    ctx.drawImage(e, 0, 0);
    const d = ctx.getImageData(0, 0, c.width, c.height).data;
    let sum = 0, sq = 0;
    const n = d.length / 4;
    for (let i = 0; i < d.length; i += 4) {
      const v = (d[i] + d[i + 1] + d[i + 2]) / 3;
      sum += v;
      sq += v * v;
    }
    const mean = sum / n;
    window.__glint = Object.assign(window.__glint || {}, { [tag]: d });
    return { w: c.width, h: c.height, mean, std: Math.sqrt(Math.max(0, sq / n - mean * mean)) };
  }, tag);
  // The first frame: not the placeholder, not uniform.
  await page.waitForFunction((minStd) => {
    const e = document.querySelector("img.renderview-view");
    if (!e || !e.complete || e.naturalWidth <= 16) return false;
    const c = document.createElement("canvas");
    c.width = 64;
    c.height = 64;
    const ctx = c.getContext("2d");
    ctx.drawImage(e, 0, 0, 64, 64);
    const d = ctx.getImageData(0, 0, 64, 64).data;
    let sum = 0, sq = 0;
    for (let i = 0; i < d.length; i += 4) {
      const v = (d[i] + d[i + 1] + d[i + 2]) / 3;
      sum += v;
      sq += v * v;
    }
    const mean = sum / (d.length / 4);
    return Math.sqrt(Math.max(0, sq / (d.length / 4) - mean * mean)) > minStd;
  }, MIN_STD, { timeout: 60000, polling: 250 });
  result.frame_s = secs();
  // Let a lossless frame follow a JPEG one (jupyter_rfb: 0.3 s later).
  await page.waitForTimeout(1000);
  const before = await stats("before");
  // A drag across the middle of the canvas.
  const box = await img.boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  for (let i = 1; i <= 20; i++) {
    await page.mouse.move(cx + i * 6, cy + i * 2);
    await page.waitForTimeout(30);
  }
  await page.mouse.up();
  // The drag's full frame (drag frames are half size; the full one follows 150 ms
  // after the last move) and its lossless copy: the <img> at full size has held the
  // same source for a second.
  // Under load the drag's first frame can take more than a second: the frame shown
  // before the drag does not count.
  const shown = () => img.evaluate((e) => `${e.naturalWidth} ${e.src}`);
  const undragged = await shown();
  let last = undragged, since = Date.now();
  const end = Date.now() + 90000;
  while (Date.now() < end &&
    (Date.now() - since < 1000 || last === undragged || !last.startsWith(`${before.w} `))) {
    await page.waitForTimeout(100);
    const now = await shown();
    if (now !== last) {
      last = now;
      since = Date.now();
    }
  }
  const after = await stats("after");
  // The mean absolute difference of the RGB values (frames of different sizes: none).
  const diff = await page.evaluate(() => {
    const { before, after } = window.__glint;
    if (before.length !== after.length) return 0;
    let sum = 0;
    for (let i = 0; i < before.length; i++) {
      if (i % 4 !== 3) sum += Math.abs(before[i] - after[i]);
    }
    return sum / (before.length * 3 / 4);
  });
  result.dragged_s = secs();
  Object.assign(result, {
    size: [[before.w, before.h], [after.w, after.h]],
    std: [+before.std.toFixed(1), +after.std.toFixed(1)],
    mean: [+before.mean.toFixed(1), +after.mean.toFixed(1)],
    diff: +diff.toFixed(2),
  });
  // The widget (canvas and panel), as the notebook shows it.
  const widget = page.locator(".widget-hbox", { has: page.locator("img.renderview-view") }).last();
  await widget.screenshot({ path: shot });
  result.ok = before.std > MIN_STD && after.std > MIN_STD && diff > MIN_DIFF;
  // What a kernel restart leaves on the page (docs/python.md tells the user): the
  // restart as the toolbar's button makes it (without its dialog), then a drag.
  await page.evaluate(() => window.jupyterapp.shell.currentWidget.sessionContext.restartKernel());
  await page.waitForFunction(() => {
    const kernel = window.jupyterapp.shell.currentWidget.sessionContext.session.kernel;
    return kernel && kernel.connectionStatus === "connected" && kernel.status === "idle";
  }, null, { timeout: 60000, polling: 250 });
  result.restarted_s = secs();
  await page.waitForTimeout(1000);
  const held = await shown();
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) await page.mouse.move(cx - i * 6, cy);
  await page.mouse.up();
  await page.waitForTimeout(2000);
  result.after_restart = await page.evaluate((held) => {
    const e = document.querySelector("img.renderview-view");
    const outputs = Array.from(document.querySelectorAll(".jp-OutputArea-output"))
      .map((o) => o.innerText.trim()).filter((t) => t);
    return {
      img: !!e,
      same_frame: !!e && `${e.naturalWidth} ${e.src}` === held,
      outputs: outputs.map((t) => t.split("\n")[0].slice(0, 120)),
    };
  }, held);
} catch (e) {
  result.error = String(e.message || e).split("\n")[0];
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
if (!result.ok) process.exitCode = 1;
