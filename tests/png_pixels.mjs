// node png_pixels.mjs FILE.png: "PIXELS GREEN" -- the image's pixel count and how many of them
// are leaf green (green above red and blue by more than 16).
// node png_pixels.mjs --diff A.png B.png: "PIXELS DIFFERING OVER32 RMSE" -- of two images of one
// size, the pixels whose RGB differ at all, those differing by more than 32 levels in a
// channel, and the RMSE over the RGB channels in levels (0..255).
// Reads what the CLI writes: 8-bit RGBA, not interlaced, any of the five row filters.
import { readFileSync } from 'node:fs';
import { inflateSync } from 'node:zlib';

function decode(path) {
  const bytes = readFileSync(path);
  let at = 8, width = 0, height = 0;
  const idat = [];
  while (at < bytes.length) {
    const len = bytes.readUInt32BE(at), type = bytes.toString('latin1', at + 4, at + 8);
    const body = bytes.subarray(at + 8, at + 8 + len);
    if (type === 'IHDR') {
      width = body.readUInt32BE(0);
      height = body.readUInt32BE(4);
      if (body[8] !== 8 || body[9] !== 6 || body[12] !== 0) throw new Error('not 8-bit RGBA');
    } else if (type === 'IDAT') idat.push(body);
    at += 12 + len;
  }
  const raw = inflateSync(Buffer.concat(idat)), stride = 4 * width;
  const px = Buffer.alloc(stride * height);
  const paeth = (a, b, c) => {
    const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
  };
  for (let y = 0; y < height; ++y) {
    const f = raw[y * (stride + 1)], row = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let x = 0; x < stride; ++x) {
      const a = x >= 4 ? px[y * stride + x - 4] : 0, b = y ? px[(y - 1) * stride + x] : 0;
      const c = x >= 4 && y ? px[(y - 1) * stride + x - 4] : 0;
      const pred = [0, a, b, (a + b) >> 1, paeth(a, b, c)][f];
      px[y * stride + x] = (row[x] + pred) & 255;
    }
  }
  return { width, height, px };
}

if (process.argv[2] === '--diff') {
  const a = decode(process.argv[3]), b = decode(process.argv[4]);
  if (a.width !== b.width || a.height !== b.height) throw new Error('the sizes differ');
  let differing = 0, over = 0, sq = 0;
  for (let i = 0; i < a.px.length; i += 4) {
    let worst = 0;
    for (let k = 0; k < 3; ++k) {
      const d = a.px[i + k] - b.px[i + k];
      sq += d * d;
      worst = Math.max(worst, Math.abs(d));
    }
    if (worst > 0) ++differing;
    if (worst > 32) ++over;
  }
  const n = a.width * a.height;
  console.log(`${n} ${differing} ${over} ${Math.sqrt(sq / (3 * n)).toFixed(2)}`);
} else {
  const { width, height, px } = decode(process.argv[2]);
  let green = 0;
  for (let i = 0; i < px.length; i += 4)
    if (px[i + 1] > px[i] + 16 && px[i + 1] > px[i + 2] + 16) ++green;
  console.log(`${width * height} ${green}`);
}
