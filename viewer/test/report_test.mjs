// compare's report.html in a real browser (headless chromium, software WebGL): it must render
// with no console or page error, show its plots (inline SVG, non-empty) and every image (decoded,
// non-zero size), and its embedded viewer must come up with a WebGL2 context.
//   node test/report_test.mjs REPORT.html [SCREENSHOT.png]
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { inBrowser } from './viewer_test.mjs';

const [reportPath, shotPath] = process.argv.slice(2);
await inBrowser(pathToFileURL(resolve(reportPath)).href, 1280, 900, async (page, problems) => {
  await page.waitForLoadState('load');
  const found = await page.evaluate(() => ({
    plots: [...document.querySelectorAll('svg')].filter((s) => s.querySelector('polyline, path, circle') && s.getBoundingClientRect().width > 100).length,
    images: [...document.images].length,
    broken: [...document.images].filter((i) => !i.complete || i.naturalWidth === 0).map((i) => i.alt || i.src.slice(0, 40)),
    frames: document.querySelectorAll('table.frames img').length,
    iframes: document.querySelectorAll('iframe').length,
  }));
  console.log('report: ' + JSON.stringify(found));
  if (found.plots < 2) problems.push(`${found.plots} plots with lines or points (expected at least 2)`);
  if (found.images < 3 || found.frames < 3) problems.push(`${found.images} images, ${found.frames} in the frames table (expected the reference and at least one run with its heat map)`);
  if (found.broken.length) problems.push(`images that do not decode: ${found.broken.join(', ')}`);
  if (found.iframes !== 1) problems.push(`${found.iframes} viewer frames (expected 1)`);
  const viewer = page.frames().find((f) => f !== page.mainFrame());
  if (viewer) {
    await viewer.waitForFunction(() => window.prtsubViewer && (window.prtsubViewer.ready || window.prtsubViewer.error), null, { timeout: 120000 });
    const status = await viewer.evaluate(() => window.prtsubViewer);
    console.log('viewer: ' + JSON.stringify(status));
    if (!status.webgl2 || status.error) problems.push(`embedded viewer: ${status.error || 'no WebGL2'}`);
  }
  if (shotPath) await page.screenshot({ path: shotPath, fullPage: true });
});
