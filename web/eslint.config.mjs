// Lint for the page's TypeScript and the test scripts (npm run lint).
import js from "@eslint/js";
import tseslint from "typescript-eslint";

export default tseslint.config(
  { ignores: ["node_modules/", "dist/", "build-tests/"] },
  js.configs.recommended,
  ...tseslint.configs.recommended,
  {
    files: ["e2e/**/*.mjs", "build.mjs", "eslint.config.mjs"],
    languageOptions: {
      // e2e callbacks passed to page.waitForFunction run in the browser (document).
      globals: { process: "readonly", console: "readonly", setTimeout: "readonly", document: "readonly" },
    },
  },
);
