// bench/web.sh's browser side: opens a thorax page RUNS times in a fresh browser (Chromium through
// SwiftShader, or Firefox through llvmpipe), and prints one JSON line a run: the first picture in the
// browser's first WebGL page (cold) and in a second tab (warm), drawn and then shown (the page's
// timings.shown_ms: the second animation frame after it), and the mean frame step over 200 steps
// (each drawn and finished), at the 3D view's size W x H.
//   node web_timing.mjs PAGE.html chromium|firefox RUNS W H
import { pathToFileURL } from 'node:url';
import { launchBrowser } from './web_common.mjs';
const [page, which, runs, W, H] = process.argv.slice(2);
async function open(b) {
    const p = await b.newPage();
    await p.setViewport({ width: 1400, height: 1200, deviceScaleFactor: 1 });
    await p.goto(pathToFileURL(page).href, { waitUntil: 'load', timeout: 60000 });
    await p.waitForFunction('window.thorax && window.thorax.ready', { timeout: 60000 });
    await p.evaluate(() => window.thorax.ready);
    await p.waitForFunction('window.thorax.timings.shown_ms > 0', { timeout: 60000 });
    return p;
}
for (let r = 0; r < Number(runs); r++) {
    const b = await launchBrowser(which, { pinned: false });
    const p1 = await open(b);
    const cold = await p1.evaluate(() => window.thorax.timings);
    await p1.close();
    const p2 = await open(b);
    const warm = await p2.evaluate(() => window.thorax.timings);
    const step = await p2.evaluate((w, h) => { window.thorax.setSize(w, h); window.thorax.benchFrames(20); return window.thorax.benchFrames(200); },
                                   Number(W), Number(H));
    console.log(JSON.stringify({ browser: await b.version(), cold: cold.first_picture_ms, cold_shown: cold.shown_ms,
                                 cold_decoded: cold.load_ms, cold_context: cold.context_ms,
                                 warm: warm.first_picture_ms, warm_shown: warm.shown_ms, warm_decoded: warm.load_ms, step }));
    await b.close();
}
