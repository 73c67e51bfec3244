// The web page of `thorax export --format html` in a real browser (Debian's Chromium, headless, WebGL
// through SwiftShader), driven by puppeteer-core through the page's test hooks (docs/design/web.md):
//   node web_browser.mjs CONFIG.json
// CONFIG: {"page": path, "out": dir for the screenshots and result.json,
//          "size": [w, h], "compare": [{"frame": F (1-based), "ref": render's PNG}, ...] (optional),
//          "series": {"SURFACE": raw series path} (optional: the picked node's plot checked against it),
//          "picks": [{"surface": S, "hide": [surfaces hidden for the click]}] or "pick": S (optional),
//          "leads": true|false, "tolerance": channel levels (default 8),
//          "min_match": fraction of the compared pixels within the tolerance (default 0.99)}
// Prints one line per check and the figures (times are printed, never judged: bench/web.sh measures them);
// writes OUT/result.json; exit 1 on the first failure.
import { readFileSync, writeFileSync, mkdirSync } from 'node:fs';
import { pathToFileURL } from 'node:url';
import { inflateRawSync } from 'node:zlib';
import { launchBrowser, comparePixels } from './web_common.mjs';

const cfg = JSON.parse(readFileSync(process.argv[2], 'utf8'));
mkdirSync(cfg.out, { recursive: true });
const result = { page: cfg.page, checks: [] };
const fail = (msg) => {
    console.error('web_browser: FAIL: ' + msg);
    result.failed = msg;
    writeFileSync(cfg.out + '/result.json', JSON.stringify(result, null, 1));
    process.exit(1);
};
const ok = (msg, fig) => {
    console.log(msg);
    result.checks.push(Object.assign({ check: msg }, fig || {}));
};

// a thorax raw series (THXSER01): frames x rows, as rows of Float64Array
function readSeries(path) {
    const b = readFileSync(path);
    if (b.toString('latin1', 0, 8) !== 'THXSER01') fail(path + ': not a thorax raw series');
    const n = Number(b.readBigUInt64LE(8)), m = Number(b.readBigUInt64LE(16));
    const v = new Float64Array(b.buffer.slice(b.byteOffset + 200 + 8 * m, b.byteOffset + 200 + 8 * m + 8 * n * m));
    return { n, m, row: (i) => Float64Array.from({ length: m }, (_, f) => v[f * n + i]) };
}

// The node of surface name whose projection a click should hit, computed from the page file: its
// description and the surface's points blob (base64, raw deflate), the view's camera as the contract
// gives it. Returns {node, x, y} (CSS pixels from the 3D view's top left).
function expectedNode(file, name, W, H, hidden = []) {
    const text = readFileSync(file, 'utf8');
    const meta = JSON.parse(/<script type="application\/json" id="thorax-page">([\s\S]*?)<\/script>/.exec(text)[1]);
    const surf = meta.surfaces.find((s) => s.name === name);
    const blob = (k) => {
        const m = new RegExp(`id="thorax-blob-${k}" data-compression="([a-z-]+)" data-bytes="\\d+">([^<]*)<`).exec(text);
        const raw = Buffer.from(m[2], 'base64');
        const b = m[1] === 'deflate-raw' ? inflateRawSync(raw) : raw;
        return new Float32Array(b.buffer.slice(b.byteOffset, b.byteOffset + b.length));
    };
    const v = meta.views[meta.view];
    const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const unit = (a) => { const l = Math.hypot(...a); return [a[0] / l, a[1] / l, a[2] / l]; };
    const back = unit(sub(v.eye, v.center)), right = unit(cross(v.up, back)), up = cross(back, right);
    const height = 1.1 * Math.max(v.extent[1], v.extent[0] / (W / H)), s = H / height;
    const proj = [];
    for (const other of meta.surfaces) {
        if (other.layer || hidden.includes(other.name)) continue;
        const P = blob(other.points);
        for (let i = 0; i < other.nodes; i++) {
            const d = sub([P[3 * i], P[3 * i + 1], P[3 * i + 2]], v.center);
            proj.push({ surface: other.name, node: i, x: W / 2 + dot(d, right) * s, y: H / 2 - dot(d, up) * s, depth: dot(d, back) });
        }
    }
    let best = null;
    for (const q of proj) {
        if (q.surface !== name || Math.abs(q.x - W / 2) > W / 4 || Math.abs(q.y - H / 2) > H / 4) continue;
        const r = Math.hypot(q.x - W / 2, q.y - H / 2);
        if (best && r >= best.r) continue;
        // in front: no node of any surface within 8 pixels on screen is nearer the eye
        if (proj.some((o) => o !== q && Math.hypot(o.x - q.x, o.y - q.y) < 8 && o.depth > q.depth + 1e-6)) continue;
        best = { node: q.node, x: q.x, y: q.y, r };
    }
    if (!best) fail(`no node of ${name} faces the camera near the middle of the view`);
    return best;
}

const browser = await launchBrowser(cfg.browser);
result.browser = (await browser.version());
try {
    const page = await browser.newPage();
    await page.setViewport({ width: 1400, height: 1200, deviceScaleFactor: 1 });
    const errors = [];
    page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
    page.on('pageerror', (e) => errors.push(String(e)));
    const t0 = Date.now();
    await page.goto(pathToFileURL(cfg.page).href, { waitUntil: 'load', timeout: 60000 });
    await page.waitForFunction('window.thorax && window.thorax.ready', { timeout: 60000 });
    await page.evaluate(() => window.thorax.ready);
    const wall = Date.now() - t0;
    if (errors.length) fail('the page logged errors: ' + errors.join(' | '));
    const timings = await page.evaluate(() => window.thorax.timings);
    const meta = await page.evaluate(() => window.thorax.meta);
    if (!meta || meta.format !== 'thorax-page') fail('window.thorax.meta is not the page\'s description');
    result.timings = timings;
    ok(`opened in ${result.browser}: ${meta.frames} frames, ${meta.surfaces.length} surfaces; the script at ` +
       `${timings.script_ms.toFixed(0)} ms, the data decoded at ${timings.load_ms.toFixed(0)} ms, the scene made at ` +
       `${timings.scene_ms.toFixed(0)} ms, the first picture at ${timings.first_picture_ms.toFixed(0)} ms ` +
       `(the browser's first WebGL page; ${wall} ms to ready, as puppeteer saw it)`, { cold: timings });
    // the same page again in a second tab: the browser's graphics already started, as a user's is
    {
        const again = await browser.newPage();
        await again.setViewport({ width: 1400, height: 1200, deviceScaleFactor: 1 });
        await again.goto(pathToFileURL(cfg.page).href, { waitUntil: 'load', timeout: 60000 });
        await again.waitForFunction('window.thorax && window.thorax.ready', { timeout: 60000 });
        await again.evaluate(() => window.thorax.ready);
        const t = await again.evaluate(() => window.thorax.timings);
        await again.close();
        result.timings_warm = t;
        const line = `opened again: the first picture at ${t.first_picture_ms.toFixed(0)} ms (the data decoded at ` +
                     `${t.load_ms.toFixed(0)} ms)`;
        ok(line, { warm: t });
    }

    // the electrodes off (render draws none without --electrodes)
    await page.evaluate(() => {
        for (const box of document.querySelectorAll('input[type=checkbox]'))
            if (/electrode/i.test(box.closest('label')?.textContent || '') && box.checked) box.click();
    });
    const [W, H] = cfg.size || meta.size;
    await page.evaluate((w, h) => { window.thorax.setSize(w, h); window.thorax.setView(window.thorax.meta.view); }, W, H);

    // screenshots against render's pictures of the same frames and camera
    const tol = cfg.tolerance ?? 8, minMatch = cfg.min_match ?? 0.99;
    for (const c of cfg.compare || []) {
        const png = readFileSync(c.ref).toString('base64');
        await page.evaluate((f) => window.thorax.setFrame(f), c.frame - 1);
        const s = await page.evaluate(comparePixels, png, tol);
        if (s.size) fail(`frame ${c.frame}: the page's picture has ${s.size[0]} pixels, render's is ${s.size[1]}x${s.size[2]}`);
        writeFileSync(`${cfg.out}/page_${c.frame}.png`, Buffer.from(s.picture, 'base64'));
        writeFileSync(`${cfg.out}/diff_${c.frame}.png`, Buffer.from(s.diff, 'base64'));
        const frac = s.match / Math.max(1, s.n);
        const line = `frame ${c.frame}: ${(100 * frac).toFixed(2)} % of ${s.n} pixels away from edges within ${tol}/255 of ` +
                     `render's (${s.shown} on the surfaces; mean difference ${s.mean.toFixed(2)}, largest ${s.maxd})`;
        if (s.shown < 0.1 * s.n) fail(`frame ${c.frame}: the surfaces cover only ${s.shown} of the compared pixels`);
        if (frac < minMatch) fail(line + `: fewer than ${(100 * minMatch).toFixed(1)} %`);
        ok(line, { frame: c.frame, match: frac, mean: s.mean, max: s.maxd, pixels: s.n });
    }

    // a frame step
    const step = await page.evaluate(() => window.thorax.benchFrames(100));
    result.frame_step_ms = step;
    if (!(step > 0)) fail(`benchFrames gave ${step}`);
    ok(`a frame step: ${step.toFixed(2)} ms (mean of 100, each drawn and finished)`, { frame_step_ms: step });

    // the slider, the leads' marker and a click on the leads move together
    const M = meta.frames;
    const slid = await page.evaluate((M) => {
        const s = document.querySelector('input[type=range]');
        const f = Math.floor(M * 0.37);
        s.value = String(f);
        s.dispatchEvent(new Event('input', { bubbles: true }));
        return { want: f, frame: window.thorax.frame(), marker: window.thorax.marker() };
    }, M);
    if (slid.frame !== slid.want || (meta.leads && slid.marker !== slid.want))
        fail(`the slider at ${slid.want}: the page is at frame ${slid.frame}, the marker at ${slid.marker}`);
    ok(`the slider moved to frame ${slid.want + 1}: the page${meta.leads ? ' and the leads\' marker' : ''} with it`);
    if (meta.leads && cfg.leads !== false) {
        const cl = await page.evaluate(() => {
            const before = window.thorax.frame();
            const c = window.thorax.clickLeads(200);
            return { before, after: window.thorax.frame(), marker: window.thorax.marker(), slider: Number(document.querySelector('input[type=range]').value), c };
        });
        if (cl.after === cl.before || cl.marker !== cl.after || cl.slider !== cl.after)
            fail(`a click on the leads: frame ${cl.before} -> ${cl.after}, marker ${cl.marker}, slider ${cl.slider}`);
        ok(`a click on the leads at x = 200 moved to frame ${cl.after + 1}: the marker and the slider with it`);
    }

    // a click on a node: the node under it is picked and its series plotted
    // clicks on nodes: each pick {surface, hide: [surfaces hidden first]} ("pick": NAME is {surface: NAME})
    const picks = cfg.picks || (cfg.pick ? [{ surface: cfg.pick }] : []);
    result.picks = [];
    for (const pk of picks) {
        const name = pk.surface, hide = pk.hide || [];
        if (!meta.surfaces.some((s) => s.name === name)) fail(`no surface ${name} in the page`);
        await page.evaluate((hide) => { for (const h of hide) window.thorax.setSurface(h, { visible: false }); }, hide);
        // the node to click, found here from the page's file alone: the camera of the view at W x H
        // (views[view], height 1.1 max(ev, eh / aspect): thx_camera_view's rule), the surface's points
        // projected; the node nearest the middle that is in front of every node near it on screen
        const target = expectedNode(cfg.page, name, W, H, hide);
        const hit = await page.evaluate((x, y) => ({ x, y, p: window.thorax.pickAt(x, y) }), target.x, target.y);
        if (!hit.p || hit.p.surface !== name || hit.p.node !== target.node)
            fail(`a click at (${target.x.toFixed(1)}, ${target.y.toFixed(1)}), on ${name} node ${target.node + 1}, picked ` +
                 (hit.p ? `${hit.p.surface} node ${hit.p.node + 1}` : 'nothing'));
        const node = hit.p.node;
        const got = await page.evaluate((name, node) => ({
            series: Array.from(window.thorax.nodeSeries(name, node)),
            plotted: Array.from(window.thorax.plotted()),
        }), name, node);
        if (got.plotted.length !== M || got.series.length !== M) fail(`the picked node's plot has ${got.plotted.length} values, not ${M}`);
        let worst = 0;
        for (let f = 0; f < M; f++) worst = Math.max(worst, Math.abs(got.plotted[f] - got.series[f]));
        if (worst > 0) fail(`the plot differs from the node's decoded series by ${worst}`);
        let line = `a click at (${hit.x.toFixed(1)}, ${hit.y.toFixed(1)}), where ${name} node ${node + 1} projects` +
                   `${hide.length ? ' (' + hide.join(', ') + ' hidden)' : ''}, picked that node; its plot is its series`;
        const fig = { surface: name, node: node + 1 };
        if (cfg.series && cfg.series[name]) {
            const ref = readSeries(cfg.series[name]).row(node);
            const surf = meta.surfaces.find((s) => s.name === name);
            const bound = surf.data.max_error;
            let e = 0;
            for (let f = 0; f < M; f++) e = Math.max(e, Math.abs(got.plotted[f] - ref[f]));
            if (!(e <= bound * (1 + 1e-6) + 1e-12)) fail(`${line}, but ${e} from the solution's (the bound ${bound})`);
            line += `, within ${e.toExponential(2)} ${meta.unit} of the solution's (the bound ${bound.toExponential(2)})`;
            Object.assign(fig, { error: e, bound });
        }
        result.picks.push(fig);
        ok(line);
        await page.evaluate((hide) => { for (const h of hide) window.thorax.setSurface(h, { visible: true }); }, hide);
    }
    // the whole page as the browser shows it
    await page.screenshot({ path: cfg.out + '/whole.png', fullPage: true });
    if (errors.length) fail('the page logged errors: ' + errors.join(' | '));
    ok('no errors in the console');
} finally {
    await browser.close();
}
writeFileSync(cfg.out + '/result.json', JSON.stringify(result, null, 1));
console.log('web_browser: OK');
