#!/usr/bin/env bash
# Builds a small report with the release binary and opens its report.html
# in headless Chromium (scripts/check_report_html.mjs): no console error,
# nothing fetched, every picture present and showing the model.
# Usage: scripts/check-report-html.sh [LODKIT_BINARY] [REPORT.html]
# With REPORT.html given, checks that file instead of building one.
# Needs /usr/bin/chromium and web/node_modules (runs `npm ci` in web/ when
# it is missing).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/lodkit}
[ -d web/node_modules/playwright-core ] || (cd web && npm ci --no-audit --no-fund)
if [ -n "${2:-}" ]; then
  node scripts/check_report_html.mjs "$2"
  exit
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$bin" -q build --out "$work/out" --levels 4 --samples 20000
node scripts/check_report_html.mjs "$work/out/report.html"
