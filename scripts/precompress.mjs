// Writes each file of a release build a second and third time, compressed: `name.br` (brotli,
// quality 11) and `name.gz` (gzip -9), beside `name`, for a web server that sends a precompressed
// file when the browser accepts it (README, "Hosting the lab"). Brotli sends the two wasm modules
// about a quarter smaller than gzip: what a slow link waits for before the first result.
//
// Trunk runs it after each build (Trunk.toml, [[hooks]]) with TRUNK_STAGING_DIR set, and skips it
// for debug builds (TRUNK_PROFILE=debug), which no one hosts; `node scripts/precompress.mjs DIR`
// compresses another directory.
import { readdir, readFile, writeFile } from 'node:fs/promises';
import { extname, join } from 'node:path';
import { promisify } from 'node:util';
import { brotliCompress, constants, gzip } from 'node:zlib';

/** What is worth compressing: text and wasm, above a size where a header costs more than it saves. */
const COMPRESSIBLE = new Set(['.wasm', '.js', '.css', '.html', '.svg', '.json', '.csv', '.md', '.fll', '.txt']);
const MIN_BYTES = 1024;

const directory = process.argv[2] ?? process.env.TRUNK_STAGING_DIR;
if (!directory) {
  console.error('precompress: give the directory to compress (or run it as a Trunk hook)');
  process.exit(2);
}
if (!process.argv[2] && process.env.TRUNK_PROFILE !== 'release') process.exit(0);

/** Every file under `dir`, recursively. */
async function* files(dir) {
  for (const entry of await readdir(dir, { withFileTypes: true })) {
    const path = join(dir, entry.name);
    if (entry.isDirectory()) yield* files(path);
    else if (entry.isFile()) yield path;
  }
}

/** Both compressed forms of `path`, written beside it; whether it was worth compressing. The
 * files compress side by side (zlib's thread pool), so a build waits for about its largest. */
async function compress(path) {
  if (!COMPRESSIBLE.has(extname(path))) return false;
  const body = await readFile(path);
  if (body.length < MIN_BYTES) return false;
  const [brotli, gzipped] = await Promise.all([
    promisify(brotliCompress)(body, {
      params: {
        [constants.BROTLI_PARAM_QUALITY]: constants.BROTLI_MAX_QUALITY,
        [constants.BROTLI_PARAM_LGWIN]: constants.BROTLI_MAX_WINDOW_BITS,
        [constants.BROTLI_PARAM_SIZE_HINT]: body.length,
      },
    }),
    promisify(gzip)(body, { level: 9 }),
  ]);
  await Promise.all([writeFile(`${path}.br`, brotli), writeFile(`${path}.gz`, gzipped)]);
  return true;
}

const paths = [];
for await (const path of files(directory)) paths.push(path);
const count = (await Promise.all(paths.map(compress))).filter(Boolean).length;
console.error(`precompress: ${count} files in ${directory} written as .br and .gz beside themselves`);
