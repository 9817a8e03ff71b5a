// Drives glint view's picking in Debian's headless Chromium through playwright-core
// (as drive.mjs): click the image, check the marker is drawn over it (pixels of the
// overlay canvas), click a second point, check the ruler between them is drawn and
// its length shown, drag, check the marks moved with the camera.
//
//   node pick.mjs URL [SHOT.png]
//
// Prints one JSON line (the two picks' world points, the reported distance, what the
// overlay held where); exits non-zero on failure.
import { chromium } from "playwright-core";

const [url, shot] = process.argv.slice(2);
if (!url) {
  console.error("usage: pick.mjs URL [SHOT.png]");
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
try {
  const page = await browser.newPage({ viewport: { width: 900, height: 640 } });
  page.on("pageerror", (e) => { console.error(`page error: ${e.message}`); process.exitCode = 1; });
  await page.goto(url);
  await page.waitForFunction(() => window.glint && window.glint.full >= 1, null, { timeout: 120000 });
  const box = await page.locator("#frame").boundingBox();
  // Alpha of the overlay at fractions (fx, fy) of the image, the most in a 5x5 patch.
  const alphaAt = (fx, fy) => page.evaluate(([fx, fy]) => {
    const o = document.getElementById("marks");
    const x = Math.round(fx * o.width), y = Math.round(fy * o.height);
    const d = o.getContext("2d").getImageData(Math.max(0, x - 2), Math.max(0, y - 2), 5, 5).data;
    let a = 0;
    for (let i = 3; i < d.length; i += 4) a = Math.max(a, d[i]);
    return a;
  }, [fx, fy]);
  const picks = () => page.evaluate(() => window.glint.pick);
  // Clicks at fractions of the image and waits for the answer and the marks drawn.
  const click = async (fx, fy, marks) => {
    const answers = (await picks()).answers;
    await page.mouse.click(box.x + fx * box.width, box.y + fy * box.height);
    await page.waitForFunction(([n, m]) => window.glint.pick.answers > n && window.glint.pick.points.length === m,
      [answers, marks], { timeout: 60000 });
    return picks();
  };
  const first = await click(0.5, 0.5, 1);
  const marker = await alphaAt(...first.points[0]);
  const second = await click(0.62, 0.45, 2);
  const [a, b] = second.points;
  const middle = await alphaAt((a[0] + b[0]) / 2, (a[1] + b[1]) / 2);
  const corner = await alphaAt(0.02, 0.98);
  const ruler = await page.locator("#pick-ruler").textContent();
  const info = await page.locator("#pick-info").textContent();
  // A drag turns the camera: the marks follow (projected with the new frames' camera).
  const full = await page.evaluate(() => window.glint.full);
  await page.mouse.move(box.x + box.width * 0.3, box.y + box.height * 0.8);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width * 0.3 + 60, box.y + box.height * 0.8, { steps: 6 });
  await page.mouse.up();
  await page.waitForFunction((n) => window.glint.full > n, full, { timeout: 120000 });
  const turned = await picks();
  const follows = await alphaAt(...turned.points[0]);
  if (shot) await page.screenshot({ path: shot });
  const errors = await page.evaluate(() => window.glint.errors);
  const report = {
    first: first.last, second: second.last, marks: second.marks, distance_mm: second.distance,
    ruler, info, marker, middle, corner, before: second.points, after: turned.points, follows, errors,
  };
  console.log(JSON.stringify(report));
  const ok = marker > 0 && middle > 0 && corner === 0 && follows > 0 && errors.length === 0;
  if (!ok) process.exitCode = 1;
} finally {
  await browser.close();
}
