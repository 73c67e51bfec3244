// What the browser tests share (tests/web_browser.mjs, tests/web_layers_check.mjs; bench/web_timing.mjs
// launches its browsers here too): launching Debian's Chromium (WebGL through SwiftShader) or Firefox
// ESR (through Mesa's llvmpipe) headless, and the in-page comparison of the page's 3D view with
// render's PNG. Copied beside them by tests/e2e_web_browser.sh and bench/web.sh (an ES module
// resolves its imports from its own folder).
import puppeteer from 'puppeteer-core';

// browser: "chromium" (CHROMIUM names the program) or "firefox" (FIREFOX). pinned (the tests'): Chromium's
// pixels at scale 1 and its page rasterized on the CPU, whatever the machine; the bench leaves
// Chromium's defaults (what a reader's browser does).
export function launchBrowser(browser, { pinned = true } = {}) {
    return puppeteer.launch(browser === 'firefox' ? {
        browser: 'firefox',
        executablePath: process.env.FIREFOX || '/usr/bin/firefox-esr',
        headless: true,
        extraPrefsFirefox: { 'webgl.force-enabled': true, 'webgl.out-of-process': false, 'gfx.webrender.software': true },
        env: { ...process.env, LIBGL_ALWAYS_SOFTWARE: '1', MOZ_WEBGL_FORCE_EGL: '1' },
    } : {
        executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
        headless: true,
        args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--ignore-gpu-blocklist',
               ...(pinned ? ['--force-device-scale-factor=1', '--disable-gpu-rasterization'] : [])],
    });
}

// Run in the page (page.evaluate(comparePixels, b64, tol)): the 3D view's pixels against the PNG (base64)
// away from the edges: pixels within 2 of a change of silhouette (not the background) in either
// picture are left out, antialiasing differing there. {n compared, match within tol, maxd, mean, shown
// (compared pixels on the surfaces), diff, picture (PNGs, base64)}, or {size} when the sizes differ.
export async function comparePixels(b64, tol) {
    const data = window.thorax.canvasPixels();
    const blob = await (await fetch('data:image/png;base64,' + b64)).blob();
    const bmp = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
    const w = bmp.width, h = bmp.height;
    const oc = new OffscreenCanvas(w, h), g = oc.getContext('2d');
    g.drawImage(bmp, 0, 0);
    const ref = g.getImageData(0, 0, w, h).data;
    if (data.length !== 4 * w * h) return { size: [data.length / 4, w, h] };
    const p = data;
    const bg = [ref[0], ref[1], ref[2]];
    const inside = (a, k) => Math.abs(a[k] - bg[0]) + Math.abs(a[k + 1] - bg[1]) + Math.abs(a[k + 2] - bg[2]) > 6;
    const sil = new Uint8Array(w * h);
    for (let i = 0; i < w * h; i++) sil[i] = (inside(ref, 4 * i) ? 1 : 0) | (inside(p, 4 * i) ? 2 : 0);
    let n = 0, match = 0, maxd = 0, sum = 0, shown = 0;
    const diff = g.createImageData(w, h);
    for (let y = 0; y < h; y++)
        for (let x = 0; x < w; x++) {
            const i = y * w + x;
            let edge = sil[i] === 1 || sil[i] === 2;
            for (let dy = -2; dy <= 2 && !edge; dy++)
                for (let dx = -2; dx <= 2 && !edge; dx++) {
                    const xx = x + dx, yy = y + dy;
                    if (xx >= 0 && yy >= 0 && xx < w && yy < h && sil[yy * w + xx] !== sil[i]) edge = true;
                }
            const k = 4 * i;
            const d = Math.max(Math.abs(p[k] - ref[k]), Math.abs(p[k + 1] - ref[k + 1]), Math.abs(p[k + 2] - ref[k + 2]));
            diff.data[k + 3] = 255;
            if (edge) { diff.data[k] = diff.data[k + 1] = diff.data[k + 2] = 200; continue; }
            n++;
            shown += sil[i] === 3;
            match += d <= tol;
            maxd = Math.max(maxd, d);
            sum += d;
            diff.data[k] = d > tol ? 255 : 255 - 8 * d;
            diff.data[k + 1] = diff.data[k + 2] = d > tol ? 0 : 255 - 8 * d;
        }
    g.putImageData(diff, 0, 0);
    const png = async (c) => {
        const b = new Uint8Array(await (await c.convertToBlob({ type: 'image/png' })).arrayBuffer());
        let s = '';
        for (let i = 0; i < b.length; i++) s += String.fromCharCode(b[i]);
        return btoa(s);
    };
    const pc = new OffscreenCanvas(w, h);
    pc.getContext('2d').putImageData(new ImageData(new Uint8ClampedArray(p), w, h), 0, 0);
    return { n, match, maxd, mean: n ? sum / n : 0, shown, diff: await png(oc), picture: await png(pc) };
}
