// The page's layers and scan planes (docs/design/web.md, "The page's data, version 1": a surface's
// `layer`, META.planes) in a real browser (Debian's Chromium, headless, WebGL through SwiftShader; or
// Firefox ESR through Mesa's llvmpipe), driven by puppeteer-core through the page's test hooks:
//   node web_layers_check.mjs CONFIG.json
// CONFIG: {"out": dir for the pictures and result.json, "tolerance": channel levels (default 8),
//          "min_match": fraction of the compared pixels within the tolerance (default 0.99),
//          "keep_going": true to run every case and fail at the end (default: stop at the first failure),
//          "browser": "chromium" (default; CHROMIUM names it) or "firefox" (FIREFOX),
//          "cases": [{"name": s, "page": path, "ref": render's PNG of the same options (optional)}, ...]}
// Per case: the page opens without errors; its picture at the frame shown first (the layers' frame)
// against render's, pixel by pixel away from the edges; the layers stay as they are at another frame
// (the model's surfaces hidden, the picture unchanged); the layers' rows say their time; clicks pick
// the model's surfaces only (never a layer, nothing where only layers and planes are); the "scan
// plane" checkbox hides and shows the planes. Writes OUT/NAME_page.png, OUT/NAME_diff.png and
// OUT/result.json; exit 1 on the first failure.
// The script must sit beside a node_modules holding puppeteer-core (scripts/web.sh installs it in
// BUILD/web/npm/node_modules): an ES module resolves its imports from its own folder.
import { readFileSync, writeFileSync, mkdirSync } from 'node:fs';
import { pathToFileURL } from 'node:url';
import { launchBrowser, comparePixels } from './web_common.mjs';

const cfg = JSON.parse(readFileSync(process.argv[2], 'utf8'));
mkdirSync(cfg.out, { recursive: true });
const result = { cases: [], failed: [] };
class CaseFailure extends Error {}
const fail = (msg) => {
    throw new CaseFailure(msg);
};
const failed = (msg) => {
    console.error('web_layers_check: FAIL: ' + msg);
    result.failed.push(msg);
    writeFileSync(cfg.out + '/result.json', JSON.stringify(result, null, 1));
    if (!cfg.keep_going) process.exit(1);
};
const tol = cfg.tolerance ?? 8, minMatch = cfg.min_match ?? 0.99;

const browser = await launchBrowser(cfg.browser);
result.browser = await browser.version();
console.log(`web_layers_check: ${result.browser}`);
try {
    for (const c of cfg.cases) {
        const fig = { name: c.name, page: c.page };
        result.cases.push(fig);
        const page = await browser.newPage();
        try {
            await runCase(c, fig, page);
        } catch (e) {
            if (!(e instanceof CaseFailure)) throw e;
            failed(e.message);
        }
        await page.close();
    }
} finally {
    await browser.close();
}
writeFileSync(cfg.out + '/result.json', JSON.stringify(result, null, 1));
if (result.failed.length) {
    console.error(`web_layers_check: ${result.failed.length} of ${cfg.cases.length} cases failed`);
    process.exit(1);
}
console.log('web_layers_check: OK');

async function runCase(c, fig, page) {
    {
        await page.setViewport({ width: 1400, height: 1200, deviceScaleFactor: 1 });
        const errors = [];
        page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
        page.on('pageerror', (e) => errors.push(String(e)));
        await page.goto(pathToFileURL(c.page).href, { waitUntil: 'load', timeout: 120000 });
        await page.waitForFunction('window.thorax && window.thorax.ready', { timeout: 120000 });
        await page.evaluate(() => window.thorax.ready);
        if (errors.length) fail(`${c.name}: the page logged errors: ${errors.join(' | ')}`);
        const info = await page.evaluate(() => {
            const T = window.thorax, m = T.meta;
            T.setSurface('electrodes', { visible: false }); // render draws none by default
            T.setSize(m.size[0], m.size[1]);
            T.setView(m.view);
            const layers = m.surfaces.map((s, i) => ({ i, name: s.name, layer: s.layer, data: !!s.data, mode: s.mode }))
                .filter((s) => s.layer);
            const notes = Array.from(document.querySelectorAll('.thx-surf label')).map((l) => l.textContent);
            return { frames: m.frames, first: m.initial_frame, size: m.size, planes: (m.planes || []).length, layers, notes,
                     timings: T.timings, bars: document.querySelectorAll('.thx-bars canvas').length };
        });
        fig.timings = info.timings;
        const head = `${c.name}: ${info.layers.length} layers (${info.layers.map((l) => l.name).join(', ')}), ` +
                     `${info.planes} planes, ${info.bars} colour bars; first picture at ${info.timings.first_picture_ms.toFixed(0)} ms`;
        console.log(head);

        // the layers' rows: "(at t = ...)" for a layer with data
        for (const l of info.layers)
            if (l.data && !info.notes.some((t) => t.startsWith(l.name) && /\(at t = [^)]*\)/.test(t)))
                fail(`${c.name}: no row "${l.name} (at t = ...)" among the surfaces' controls: ${info.notes.join(' | ')}`);

        // the picture against render's
        if (c.ref) {
            const png = readFileSync(c.ref).toString('base64');
            const s = await page.evaluate(comparePixels, png, tol);
            if (s.size) fail(`${c.name}: the page's picture has ${s.size[0]} pixels, render's is ${s.size[1]}x${s.size[2]}`);
            writeFileSync(`${cfg.out}/${c.name}_page.png`, Buffer.from(s.picture, 'base64'));
            writeFileSync(`${cfg.out}/${c.name}_diff.png`, Buffer.from(s.diff, 'base64'));
            const frac = s.match / Math.max(1, s.n);
            const line = `${c.name}: ${(100 * frac).toFixed(2)} % of ${s.n} pixels away from edges within ${tol}/255 of render's ` +
                         `(${s.shown} on the surfaces; mean difference ${s.mean.toFixed(2)}, largest ${s.maxd})`;
            Object.assign(fig, { match: frac, pixels: s.n, shown: s.shown, mean: s.mean, max: s.maxd });
            if (s.shown < 0.1 * s.n) fail(`${line}: the surfaces cover too few of the compared pixels`);
            if (frac < minMatch) fail(`${line}: fewer than ${(100 * minMatch).toFixed(1)} %`);
            console.log(line);
        }

        // the layers do not follow the frame: the model's surfaces hidden, two frames' pictures equal
        if (info.frames > 1 && info.layers.length) {
            const same = await page.evaluate((first) => {
                const T = window.thorax, m = T.meta;
                m.surfaces.forEach((s, i) => { if (!s.layer) T.setSurface(i, { visible: false }); });
                T.setFrame(first);
                const a = T.canvasPixels();
                T.setFrame((first + Math.floor(m.frames / 2)) % m.frames);
                const b = T.canvasPixels();
                let diff = 0, bgd = 0;
                for (let k = 0; k < a.length; k++) diff += a[k] !== b[k];
                for (let k = 4; k < a.length; k += 4) bgd += a[k] !== a[0] || a[k + 1] !== a[1] || a[k + 2] !== a[2];
                m.surfaces.forEach((s, i) => { if (!s.layer) T.setSurface(i, { visible: s.visible !== false && s.mode !== 'hidden' }); });
                T.setFrame(first);
                return { diff, drawn: bgd };
            }, info.first);
            if (same.diff) fail(`${c.name}: the layers alone changed by ${same.diff} channel values from one frame to another`);
            if (!same.drawn) console.log(`${c.name}: the layers alone draw nothing in this view (seen edge-on?): not checked`);
            else console.log(`${c.name}: the layers alone (${same.drawn} pixels) are the same at another frame`);
            fig.layers_fixed = same.drawn > 0;
        }

        // clicks pick the model's surfaces only
        const picks = await page.evaluate((W, H) => {
            const T = window.thorax, m = T.meta;
            const out = { model: 0, layer: 0, none: 0 };
            for (let y = 16; y < H; y += 32)
                for (let x = 16; x < W; x += 32) {
                    const p = T.pickAt(x, y);
                    if (!p) out.none++;
                    else if (m.surfaces.some((s) => s.layer && s.name === p.surface) &&
                             !m.surfaces.some((s) => !s.layer && s.name === p.surface && s.mode !== 'hidden')) out.layer++;
                    else out.model++;
                }
            out.modelShown = m.surfaces.some((s) => !s.layer && s.mode !== 'hidden');
            return out;
        }, info.size[0], info.size[1]);
        if (picks.layer) fail(`${c.name}: ${picks.layer} clicks picked a layer`);
        if (picks.modelShown && !picks.model) fail(`${c.name}: no click picked a model's surface`);
        if (!picks.modelShown && picks.model) fail(`${c.name}: ${picks.model} clicks picked a hidden model's surface`);
        console.log(`${c.name}: clicks on a 32-pixel grid: ${picks.model} picked the model's surfaces, ${picks.none} nothing, none a layer`);

        // the scan plane's checkbox
        if (info.planes) {
            const pl = await page.evaluate(() => {
                const T = window.thorax;
                const count = (a) => {
                    let n = 0;
                    for (let k = 4; k < a.length; k += 4) n += a[k] !== a[0] || a[k + 1] !== a[1] || a[k + 2] !== a[2];
                    return n;
                };
                const box = Array.from(document.querySelectorAll('.thx-surf label'))
                    .find((l) => l.textContent.startsWith('scan plane'))?.querySelector('input');
                if (!box) return null;
                const on = count(T.canvasPixels());
                box.click();
                const off = count(T.canvasPixels());
                box.click();
                const again = count(T.canvasPixels());
                T.setSurface('scan plane', { visible: false });
                const hook = count(T.canvasPixels());
                T.setSurface('scan plane', { visible: true });
                return { on, off, again, hook };
            });
            if (!pl) fail(`${c.name}: no "scan plane" checkbox`);
            if (!(pl.off < pl.on) || pl.again !== pl.on || pl.hook !== pl.off)
                fail(`${c.name}: the scan plane's checkbox: ${pl.on} pixels drawn, ${pl.off} without the planes, ${pl.again} with them again, ${pl.hook} hidden by the hook`);
            console.log(`${c.name}: the "scan plane" checkbox: ${pl.on} pixels drawn with the planes, ${pl.off} without`);
        }
        await page.screenshot({ path: `${cfg.out}/${c.name}_whole.png`, fullPage: true });
        if (errors.length) fail(`${c.name}: the page logged errors: ${errors.join(' | ')}`);
    }
}
