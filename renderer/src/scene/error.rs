//! Scene errors: every one names the file, the line and column, and the field.

use std::path::Path;

/// A problem in a scene file, located at a field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}:{column}: {field}: {message}")]
pub struct SceneError {
    /// The scene file.
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
    /// Dotted path of the field, e.g. `objects[2].transform[0].scale`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// Source text plus file name: turns byte offsets into line and column.
pub struct Source<'a> {
    /// File name as given.
    pub file: String,
    /// The text.
    pub text: &'a str,
}

impl<'a> Source<'a> {
    /// A named source.
    pub fn new(file: &Path, text: &'a str) -> Self {
        Source {
            file: file.display().to_string(),
            text,
        }
    }

    /// 1-based line and column of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        (line, column)
    }

    /// The offset of `key = ...` inside the byte range `within` (a table), or the range's
    /// start when the key is not written there (a default value is at fault).
    pub fn key_offset(&self, within: std::ops::Range<usize>, key: &str) -> usize {
        // A `[table]` header's span covers only the header: its keys run to the next header.
        let end = within
            .end
            .max(self.next_header(within.start))
            .min(self.text.len());
        let text = &self.text[within.start.min(end)..end];
        let bytes = text.as_bytes();
        let mut from = 0;
        while let Some(k) = text[from..].find(key) {
            let at = from + k;
            let before_ok =
                at == 0 || !(bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_');
            let rest = text[at + key.len()..].trim_start();
            if before_ok && rest.starts_with('=') {
                return within.start + at;
            }
            from = at + key.len();
        }
        within.start
    }

    /// The offset of the first `[table]` or `[[array]]` header line after `from`'s line
    /// (or the end of the text).
    fn next_header(&self, from: usize) -> usize {
        let mut pos = self.text[from.min(self.text.len())..]
            .find('\n')
            .map_or(self.text.len(), |k| from + k + 1);
        while pos < self.text.len() {
            let line_end = self.text[pos..]
                .find('\n')
                .map_or(self.text.len(), |k| pos + k);
            let line = self.text[pos..line_end].trim_start();
            let name = line.trim_start_matches('[');
            if line.starts_with('[')
                && name.starts_with(|c: char| c.is_alphabetic() || c == '"' || c == '\'')
            {
                return pos;
            }
            pos = line_end + 1;
        }
        self.text.len()
    }

    /// An error at a key inside a table's span.
    pub fn key_error(
        &self,
        within: std::ops::Range<usize>,
        key: &str,
        field: impl Into<String>,
        message: impl std::fmt::Display,
    ) -> SceneError {
        self.error(self.key_offset(within, key), field, message)
    }

    /// An error at a byte offset.
    pub fn error(
        &self,
        offset: usize,
        field: impl Into<String>,
        message: impl std::fmt::Display,
    ) -> SceneError {
        let (line, column) = self.line_col(offset);
        SceneError {
            file: self.file.clone(),
            line,
            column,
            field: field.into(),
            message: message.to_string(),
        }
    }
}
