// Damaged pages in the browser (tests/e2e_web_browser.sh): a page of `thorax export --format html`,
// spoiled one way at a time, must never be shown half-read. Each copy is opened in Chromium and must
// either show the page's waiting text (cut short: the viewer, which comes last, never runs) or reject
// window.thorax.ready with the message the page then shows, naming the part at fault.
//   node web_damaged_check.mjs PAGE.html OUTDIR
import { readFileSync, writeFileSync, mkdirSync } from 'node:fs';
import { pathToFileURL } from 'node:url';
import { launchBrowser } from './web_common.mjs';

const [pagePath, out] = process.argv.slice(2);
mkdirSync(out, { recursive: true });
const text = readFileSync(pagePath, 'utf8');
const fail = (msg) => {
    console.error('web_damaged_check: FAIL: ' + msg);
    process.exit(1);
};

// Blob k's element: [start of its text, end of its text, data-bytes].
function blobText(k) {
    const re = new RegExp(`<script type="application/octet-stream" id="thorax-blob-${k}" data-compression="[a-z-]+" data-bytes="(\\d+)">`);
    const m = re.exec(text);
    if (!m) fail(`the page has no blob ${k}`);
    const start = m.index + m[0].length, end = text.indexOf('</script>', start);
    return { start, end, bytes: Number(m[1]), tag: m[0] };
}
const b3 = blobText(3), b4 = blobText(4);
const garbage = Buffer.from(Array.from({ length: 600 }, (_, i) => (i * 97 + 13) & 255)); // not a deflate stream
const metaAt = text.indexOf('{"format":"thorax-page"');
if (metaAt < 0) fail('no description in the page');

// name: [the spoiled page, what must happen: {waiting: true} or {message: pattern}]
const cases = [
    ['cut short in a blob', text.slice(0, Math.floor(text.length / 2)), { waiting: true }],
    ['cut short before the viewer ends', text.slice(0, text.length - 2000), { waiting: true }],
    ['a character that is not base64', text.slice(0, b3.start + 10) + '*' + text.slice(b3.start + 11),
        { message: /blob 3 is not valid base64/ }],
    ['a blob that is not deflate', text.slice(0, b4.start) + garbage.toString('base64') + text.slice(b4.end), { message: /blob 4 does not inflate/ }],
    ['data-bytes that disagree', text.replace(b4.tag, b4.tag.replace(`data-bytes="${b4.bytes}"`, `data-bytes="${b4.bytes + 8}"`)),
        { message: new RegExp(`blob 4 holds ${b4.bytes} bytes after decompression, data-bytes says ${b4.bytes + 8}`) }],
    ['a blob missing', text.replace(b4.tag, b4.tag.replace('thorax-blob-4', 'thorax-blob-x')),
        { message: /blob 4 is missing/ }],
    ['a description that is not JSON', text.slice(0, metaAt) + text.slice(metaAt + 1), { message: /is not valid JSON/ }],
    ['a later version', text.replace('{"format":"thorax-page","version":1,', '{"format":"thorax-page","version":2,'),
        { message: /version 2; this viewer reads version 1/ }],
];

const browser = await launchBrowser('chromium');
let n = 0;
for (const [name, spoiled, want] of cases) {
    const file = `${out}/damaged_${n++}.html`;
    writeFileSync(file, spoiled);
    const page = await browser.newPage();
    const uncaught = [];
    page.on('pageerror', (e) => uncaught.push(String(e)));
    await page.goto(pathToFileURL(file).href, { waitUntil: 'load', timeout: 60000 });
    if (want.waiting) {
        await new Promise((r) => setTimeout(r, 1500)); // time for a viewer to start, had it been there
        const seen = await page.evaluate(() => {
            const w = document.getElementById('thorax-waiting');
            return { hooks: !!(window.thorax && window.thorax.ready), text: w ? w.textContent : null, shown: !!w && w.offsetHeight > 0 };
        });
        if (seen.hooks) fail(`${name}: the viewer ran`);
        if (!seen.shown || !/cut short/.test(seen.text)) fail(`${name}: the waiting text is not shown (${JSON.stringify(seen)})`);
        console.log(`${name}: the page says "${seen.text.slice(0, 60)}..."`);
    } else {
        // (window.thorax alone is the <div id="thorax"> until the viewer sets its hooks)
        await page.waitForFunction('!!(window.thorax && window.thorax.ready)', { timeout: 60000 });
        const got = await page.evaluate(async () => {
            try {
                await window.thorax.ready;
                return { ready: true };
            } catch (e) {
                const shown = document.querySelector('.thx-error');
                return { ready: false, message: e.message, shown: shown ? shown.textContent : null,
                         visible: !!shown && shown.offsetHeight > 0, canvas: document.querySelectorAll('canvas').length,
                         waiting: !!document.getElementById('thorax-waiting') };
            }
        });
        if (got.ready) fail(`${name}: the page opened`);
        if (!want.message.test(got.message)) fail(`${name}: the message "${got.message}" does not match ${want.message}`);
        if (!got.visible || got.shown !== `This page cannot be shown: ${got.message}`)
            fail(`${name}: the page does not show the message (${JSON.stringify(got)})`);
        if (got.canvas) fail(`${name}: a picture was drawn (${got.canvas} canvases)`);
        if (got.waiting) fail(`${name}: the waiting text is still there`);
        console.log(`${name}: refused, "${got.message}"`);
    }
    if (uncaught.length) fail(`${name}: uncaught errors: ${uncaught.join(' | ')}`);
    await page.close();
}
await browser.close();
console.log(`web_damaged_check: ${cases.length} damaged pages, none shown half-read`);
