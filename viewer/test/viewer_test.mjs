// The viewer in a real browser: Debian's chromium, headless, with software WebGL (SwiftShader),
// driven by playwright-core. Loads PAGE at the view QUERY describes, fails on any console error
// or page error, on a missing WebGL2 context, or when the canvas differs from REFERENCE (the
// PNG `prtsub render` wrote for the same asset, light and camera): more than 0.5% of the covered
// pixels covered in one frame only or hitting another triangle, or a PSNR below MIN_DB over the
// pixels that agree (docs/viewer.md explains the numbers). REFERENCE "-" only loads the page.
//   node test/viewer_test.mjs PAGE.html REFERENCE.png|- QUERY MIN_DB [SCREENSHOT.png]
// QUERY is the page's URL parameters (docs/viewer.md) and must hold size=W,H.
import { readFileSync, writeFileSync } from 'node:fs';
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';
import { PNG } from 'pngjs';

export const CHROMIUM_ARGS = ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-dev-shm-usage',
  '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'];

export async function openPage(url, width, height) {
  const browser = await chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium', args: CHROMIUM_ARGS });
  const page = await browser.newPage({ viewport: { width, height }, deviceScaleFactor: 1 });
  const problems = [];
  page.on('console', (m) => m.type() === 'error' && problems.push(`console error: ${m.text()}`));
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  await page.goto(url);
  return { browser, page, problems };
}

// Opens `url` at width × height, runs `body(page, problems)`, closes the browser, prints each
// problem (console and page errors included) and exits 1 if there was any.
export async function inBrowser(url, width, height, body) {
  const { browser, page, problems } = await openPage(url, width, height);
  try {
    await body(page, problems);
  } catch (e) {
    problems.push(`test: ${e.message}`);
  } finally {
    await browser.close();
  }
  for (const p of problems) console.log('FAIL ' + p);
  process.exit(problems.length ? 1 : 0);
}

async function main() {
  const [pagePath, referencePath, query, minDb, shotPath] = process.argv.slice(2);
  if (!minDb) {
    console.error('usage: node test/viewer_test.mjs PAGE.html REFERENCE.png QUERY MIN_DB [SCREENSHOT.png]');
    process.exit(2);
  }
  const [width, height] = new URLSearchParams(query).get('size').split(',').map(Number);
  const url = pathToFileURL(resolve(pagePath)).href + '?' + query;
  await inBrowser(url, width, height, async (page, problems) => {
    await page.waitForFunction(() => window.prtsubViewer && (window.prtsubViewer.ready || window.prtsubViewer.error), null, { timeout: 120000 });
    const status = await page.evaluate(() => window.prtsubViewer);
    const context = await page.evaluate(() => {
      const gl = document.getElementById('view').getContext('webgl2');
      return gl ? gl.getParameter(gl.VERSION) + ' / ' + gl.getParameter(gl.RENDERER) : null;
    });
    console.log(`status: ${JSON.stringify(status)}; context: ${context}`);
    if (!status.webgl2 || !context) problems.push('no WebGL2 context');
    if (status.error) problems.push(`viewer error: ${status.error}`);
    const shot = PNG.sync.read(await page.locator('#view').screenshot({ omitBackground: true }));
    if (shotPath) writeFileSync(shotPath, PNG.sync.write(shot));
    const ref = referencePath === '-' ? null : PNG.sync.read(readFileSync(referencePath));
    if (!ref) console.log('result: loaded, no reference to compare');
    else if (shot.width !== ref.width || shot.height !== ref.height) problems.push(`canvas ${shot.width}x${shot.height}, reference ${ref.width}x${ref.height}`);
    else {
      // Coverage is alpha (the canvas clears to transparent in test mode, the tool's uncovered
      // pixels are transparent). Where both cover a pixel, a difference above 8 of 255 means a
      // different triangle was hit (occlusion edges, where rasterisation and ray casting may
      // disagree by a pixel); the rest must agree to 8-bit rounding.
      let se = 0, seClose = 0, close = 0, both = 0, coverage = 0, far = 0;
      for (let i = 0; i < ref.width * ref.height; ++i) {
        const a = shot.data[4 * i + 3] > 0, b = ref.data[4 * i + 3] > 0;
        let e = 0, worst = 0;
        for (let c = 0; c < 3; ++c) {
          const d = (shot.data[4 * i + c] * shot.data[4 * i + 3]) / 255 - (ref.data[4 * i + c] * ref.data[4 * i + 3]) / 255;
          e += d * d, worst = Math.max(worst, Math.abs(d));
        }
        se += e;
        if (a !== b) ++coverage;
        if (!a || !b) continue;
        ++both;
        if (worst > 8) ++far;
        else seClose += e, ++close;
      }
      const psnr = (s, n) => 10 * Math.log10((255 * 255) / Math.max(s / (3 * n), 1e-12));
      const result = { psnr_db: psnr(se, ref.width * ref.height), psnr_agreeing_db: psnr(seClose, close), covered_pixels: both,
        coverage_mismatches: coverage, other_triangle_pixels: far, min_db: Number(minDb) };
      console.log('result: ' + JSON.stringify(result));
      if (both < 100) problems.push(`only ${both} pixels covered in both frames`);
      if (coverage > 0.005 * both) problems.push(`${coverage} pixels covered in one frame only (over 0.5% of ${both})`);
      if (far > 0.005 * both) problems.push(`${far} pixels differ by more than 8/255 (over 0.5% of ${both})`);
      if (result.psnr_agreeing_db < Number(minDb)) problems.push(`PSNR ${result.psnr_agreeing_db.toFixed(2)} dB over the agreeing pixels < ${minDb} dB`);
    }
  });
}

if (import.meta.url === pathToFileURL(process.argv[1]).href) await main();
