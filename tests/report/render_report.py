#!/usr/bin/env python3
"""Writes report.html from the page template and a report_data.json, as `lash report` does.

    render_report.py DATA.json -o report.html [--template BUILD/report/report_template.html]

Without --template the template is assembled here from report/template.html, report.js,
report.css and report/node_modules/uplot/dist (the same inlining report/embed_report.cmake does at
build time). The data goes in place of the one __LASH_REPORT_DATA__ token, with every "</"
written "<\\/" and every "<!--" written "<\\u0021--" so that nothing in the JSON can end or
confuse the <script> element that holds it (both are valid JSON escapes inside strings, the only
place "<" can occur in JSON).
"""
import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REPORT = os.path.join(ROOT, "report")
PLACEHOLDER = "__LASH_REPORT_DATA__"
INLINE = {  # token in template.html -> file whose text replaces it
    "@@LASH_UPLOT_CSS@@": os.path.join(REPORT, "node_modules", "uplot", "dist", "uPlot.min.css"),
    "@@LASH_REPORT_CSS@@": os.path.join(REPORT, "report.css"),
    "@@LASH_UPLOT_JS@@": os.path.join(REPORT, "node_modules", "uplot", "dist", "uPlot.iife.min.js"),
    "@@LASH_REPORT_JS@@": os.path.join(REPORT, "report.js"),
}


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def assemble_template():
    missing = [p for p in INLINE.values() if not os.path.exists(p)]
    if missing:
        sys.exit(f"render_report.py: missing {missing[0]}; run `make deps` (scripts/install-deps.sh), "
                 "which runs `npm ci` in report/")
    html = read(os.path.join(REPORT, "template.html"))
    for token, path in INLINE.items():
        if html.count(token) != 1:
            sys.exit(f"render_report.py: template.html must hold {token} exactly once")
        html = html.replace(token, read(path).strip())
    return html


def escape_json_for_script(text):
    return text.replace("</", "<\\/").replace("<!--", "<\\u0021--")


def render(template, data_text):
    if template.count(PLACEHOLDER) != 1:
        sys.exit(f"render_report.py: the template must hold {PLACEHOLDER} exactly once, "
                 f"found {template.count(PLACEHOLDER)}")
    json.loads(data_text)  # fail here, not in the browser, on broken data
    return template.replace(PLACEHOLDER, escape_json_for_script(data_text.strip()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data", help="report_data.json")
    ap.add_argument("-o", "--output", required=True, help="report.html to write")
    ap.add_argument("--template", help="generated template (default: assemble from report/ sources)")
    ap.add_argument("--write-template", help="also write the assembled template to this path")
    args = ap.parse_args()
    template = read(args.template) if args.template else assemble_template()
    if args.write_template:
        with open(args.write_template, "w", encoding="utf-8") as f:
            f.write(template)
    html = render(template, read(args.data))
    with open(args.output, "w", encoding="utf-8") as f:
        f.write(html)
    print(f"wrote {args.output} ({os.path.getsize(args.output) / 1024:.0f} KiB)", file=sys.stderr)


if __name__ == "__main__":
    main()
