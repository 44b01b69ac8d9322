// The viewer under the mouse (headless chromium): a drag turns the camera, a shift-drag turns the
// light, the wheel moves the camera, and the panel's light menu and view buttons relight; each must
// redraw (the frame counter goes up) and change the picture, with no console or page error.
//   node test/interaction_test.mjs PAGE.html
import { createHash } from 'node:crypto';
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { inBrowser } from './viewer_test.mjs';

await inBrowser(pathToFileURL(resolve(process.argv[2])).href + '?size=600,400', 800, 500, async (page, problems) => {
  await page.waitForFunction(() => window.prtsubViewer && (window.prtsubViewer.ready || window.prtsubViewer.error), null, { timeout: 120000 });
  const canvas = page.locator('#view');
  const look = async () => ({
    frames: await page.evaluate(() => window.prtsubViewer.frames),
    hash: createHash('sha256').update(await canvas.screenshot()).digest('hex'),
  });
  const box = await canvas.boundingBox();
  const cx = box.x + box.width * 0.8, cy = box.y + box.height * 0.75;  // clear of the panel (top left, 354 px wide)
  const drag = async (shift) => {
    if (shift) await page.keyboard.down('Shift');
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    await page.mouse.move(cx - 60, cy - 20, { steps: 4 });
    await page.mouse.up();
    if (shift) await page.keyboard.up('Shift');
  };
  const steps = [
    ['drag turns the camera', () => drag(false)],
    ['shift-drag turns the light', () => drag(true)],
    ['the wheel moves the camera', async () => { await page.mouse.move(cx, cy); await page.mouse.wheel(0, 300); }],
    ['the light menu relights', () => page.selectOption('#panel select', 'sun:0.5,1,0.6,2')],
    ['the AO view', () => page.check('#panel input[value=ao]')],
    ['the error view', () => page.check('#panel input[value=error]')],
  ];
  let before = await look();
  for (const [what, act] of steps) {
    if (what === 'the error view' && (await page.locator('#panel input[value=error]').isDisabled())) {
      console.log(`${what}: disabled (a page without --source)`);
      continue;
    }
    await act();
    await page.waitForTimeout(100);
    const after = await look();
    const ok = after.frames > before.frames && after.hash !== before.hash;
    console.log(`${what}: ${after.frames - before.frames} redraws, picture ${after.hash !== before.hash ? 'changed' : 'unchanged'}`);
    if (!ok) problems.push(`${what}: no redraw or no change`);
    before = after;
  }
});
