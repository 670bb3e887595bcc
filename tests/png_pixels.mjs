// node png_pixels.mjs FILE.png: "PIXELS GREEN" -- the image's pixel count and how many of them
// are leaf green (green above red and blue by more than 16). Reads what the CLI writes: 8-bit
// RGBA, not interlaced, any of the five row filters.
import { readFileSync } from 'node:fs';
import { inflateSync } from 'node:zlib';

const bytes = readFileSync(process.argv[2]);
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
let green = 0;
for (let i = 0; i < px.length; i += 4)
  if (px[i + 1] > px[i] + 16 && px[i + 1] > px[i + 2] + 16) ++green;
console.log(`${width * height} ${green}`);
