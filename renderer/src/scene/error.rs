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
