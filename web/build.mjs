// Bundles the page (src/main.ts) with esbuild into OUTDIR (default dist/): index.html,
// app.js, app.css. CMake embeds those files into rackcat (cmake/EmbedWebAssets.cmake).
// `node build.mjs --tests` bundles test/*.test.ts into build-tests/ for `node --test`.
import { build } from "esbuild";
import { copyFileSync, mkdirSync, readdirSync } from "node:fs";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);

if (args.includes("--tests")) {
  const tests = readdirSync(join(here, "test"))
    .filter((f) => f.endsWith(".test.ts"))
    .map((f) => join(here, "test", f));
  await build({
    entryPoints: tests,
    outdir: join(here, "build-tests"),
    outExtension: { ".js": ".mjs" },
    bundle: true,
    platform: "node",
    format: "esm",
    target: "node18",
    external: ["node:*"],
    logLevel: "warning",
  });
} else {
  const at = args.indexOf("--outdir");
  const outdir = resolve(at >= 0 ? args[at + 1] : join(here, "dist"));
  mkdirSync(outdir, { recursive: true });
  await build({
    entryPoints: [join(here, "src", "main.ts")],
    outfile: join(outdir, "app.js"),
    bundle: true,
    minify: true,
    format: "iife",
    target: "es2020",
    legalComments: "none",
    logLevel: "warning",
  });
  copyFileSync(join(here, "src", "index.html"), join(outdir, "index.html"));
  copyFileSync(join(here, "src", "app.css"), join(outdir, "app.css"));
}
