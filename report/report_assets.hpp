// The page template of `lash report`: one self-contained HTML file with uPlot, report.js and
// report.css inlined at build time (report/CMakeLists.txt, report/embed_report.cmake).
#pragma once

#include <string_view>

namespace lash {

/// The token that stands, exactly once, where the report data goes:
/// `<script id="lash-data" type="application/json">__LASH_REPORT_DATA__</script>`.
inline constexpr std::string_view kReportDataPlaceholder = "__LASH_REPORT_DATA__";

/// The report page template (UTF-8 HTML, about 120 kB), holding kReportDataPlaceholder once.
/// The caller replaces the placeholder by the report_data.json text (docs/report-data.md) with
/// every "</" written "<\/" (and "<!--" written "<\u0021--"), so that the JSON cannot end the
/// <script> element; both are valid JSON escapes inside strings, the only place '<' occurs.
/// The page makes no network request. Never throws; the view refers to static storage.
std::string_view report_html_template();

}  // namespace lash
