//! Text made safe to put in the report's HTML.

/// `s` with the characters HTML gives a meaning to (`&`, `<`, `>`, `"`) escaped.
pub(super) fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
