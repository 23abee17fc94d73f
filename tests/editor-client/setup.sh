#!/usr/bin/env bash
# setup.sh: installs what tests/editor.rs needs, once.
# - node_modules (puppeteer-core, pinned in package-lock.json) by `npm ci` when it is missing;
# - Debian's chromium (headless, WebGL 2 on SwiftShader) by apt-get when /usr/bin/chromium is
#   missing (needs root and the Debian package registry), as tests/gltf-client/setup.sh.
# Exit 0 when everything is in place, 2 on a set-up problem (the log is named).
set -u
cd "$(dirname "$0")" || exit 2
log="${TMPDIR:-/tmp}/grainline-editor-client-setup.log"
command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1 \
  || { echo "setup.sh: node and npm are needed (Debian: apt-get install nodejs npm)" >&2; exit 2; }
if [[ ! -d node_modules/puppeteer-core ]]; then
  echo "setup.sh: npm ci (puppeteer-core) ..." >&2
  npm ci --no-audit --no-fund >"$log" 2>&1 \
    || { echo "setup.sh: npm ci failed; see $log" >&2; exit 2; }
fi
chromium="${GRAINLINE_CHROMIUM:-/usr/bin/chromium}"
if [[ ! -x $chromium ]]; then
  echo "setup.sh: installing chromium ..." >&2
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium; } >>"$log" 2>&1 \
    || { echo "setup.sh: could not install chromium; see $log" >&2; exit 2; }
fi
exit 0
