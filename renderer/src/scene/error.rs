//! Scene errors: every one names the file, and the line, column and field when the
//! problem is at one (a file that cannot be read has none).

use std::path::Path;

/// A problem in a scene file, located at a field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SceneError {
    /// The scene file.
    pub file: String,
    /// 1-based line; 0 when the problem is at no place in the text (the file cannot be
    /// read, or a command-line option is wrong).
    pub line: usize,
    /// 1-based column (in characters); 0 with line 0.
    pub column: usize,
    /// Dotted path of the field, e.g. `objects[2].transform[0].scale`, or what is at fault
    /// when there is no field (`--spp`); empty when that is the file itself.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for SceneError {
    /// `FILE:LINE:COLUMN: FIELD: MESSAGE`, leaving out a location there is not.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.file)?;
        if self.line > 0 {
            write!(f, ":{}:{}", self.line, self.column)?;
        }
        if !self.field.is_empty() {
            write!(f, ": {}", self.field)?;
        }
        write!(f, ": {}", self.message)
    }
}

impl SceneError {
    /// An error about the whole file (or the command line), at no line.
    pub fn unlocated(
        file: &Path,
        field: impl Into<String>,
        message: impl std::fmt::Display,
    ) -> SceneError {
        SceneError {
            file: file.display().to_string(),
            line: 0,
            column: 0,
            field: field.into(),
            message: message.to_string(),
        }
    }
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

/// Rewords a message of the TOML deserializer for a scene file's reader: an unknown key
/// or value says so in one wording, with a "did you mean" (`crate::suggest`) and the
/// choices; Rust's type names become words (`f64` is "a number"). `is_key` says whether
/// the unknown name of an enum was written as a key (`[camera.lookat]`,
/// `{ translat = … }`) rather than as a value (`type = "torus"`). Any other message is
/// returned as it is.
pub fn reword(message: &str, is_key: bool) -> String {
    if let Some((kind, names, choices)) = unknown_names(message) {
        let what = if kind == "field" || is_key {
            "key"
        } else {
            "value"
        };
        let named: Vec<String> = names
            .iter()
            .map(|n| {
                let hint = crate::suggest::did_you_mean(n, choices.iter().copied());
                format!("`{n}`{hint}")
            })
            .collect();
        let list = if choices.is_empty() {
            format!("no {what}s are allowed here")
        } else {
            format!("the {what}s allowed here: {}", choices.join(", "))
        };
        let plural = if names.len() > 1 { "s" } else { "" };
        return format!("unknown {what}{plural} {}; {list}", named.join(", "));
    }
    if message.starts_with("data did not match any variant of untagged enum ScaleArg") {
        return "expected a number (a uniform scale) or an array of 3 numbers (one per axis)"
            .into();
    }
    let mut m = message.to_string();
    for (rust, words) in [
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
        (
            "expected u32",
            "expected a whole number from 0 to 4294967295",
        ),
        ("expected u64", "expected a whole number ≥ 0"),
        ("expected usize", "expected a whole number ≥ 0"),
    ] {
        if let Some(head) = m.strip_suffix(rust) {
            m = format!("{head}{words}");
        }
    }
    m
}

/// Parses the deserializer's messages about unknown names into the kind (`field` or
/// `variant`), the names and the choices. serde: `unknown field `X`, expected `a``, `…,
/// expected `a` or `b``, `…, expected one of `a`, `b`, …`, `…, there are no fields`, and
/// the same with `variant`; toml, for a table in an enum: `unexpected keys in table: X, Y,
/// available keys: a, b`.
fn unknown_names(message: &str) -> Option<(&str, Vec<&str>, Vec<&str>)> {
    if let Some(rest) = message.strip_prefix("unexpected keys in table: ") {
        let (names, choices) = rest.split_once(", available keys: ")?;
        let names = names.split(", ").collect();
        let choices = choices.split(", ").filter(|c| !c.is_empty()).collect();
        return Some(("field", names, choices));
    }
    let rest = message.strip_prefix("unknown ")?;
    let (kind, rest) = rest.split_once(" `")?;
    if kind != "field" && kind != "variant" {
        return None;
    }
    let (name, rest) = rest.split_once('`')?;
    let choices = rest.split('`').skip(1).step_by(2).collect();
    Some((kind, vec![name], choices))
}

#[cfg(test)]
mod tests {
    use super::reword;

    #[test]
    fn test01_unknown_keys_and_values_read_alike() {
        assert_eq!(
            reword(
                "unknown field `radiuss`, expected one of `type`, `radius`",
                false
            ),
            "unknown key `radiuss` (did you mean 'radius'?); the keys allowed here: type, radius"
        );
        assert_eq!(
            reword("unknown variant `lookat`, expected one of `view`, `look_at`, `povray`", true),
            "unknown key `lookat` (did you mean 'look_at'?); the keys allowed here: view, look_at, povray"
        );
        assert_eq!(
            reword("unknown variant `sphre`, expected `sphere` or `plane`", false),
            "unknown value `sphre` (did you mean 'sphere'?); the values allowed here: sphere, plane"
        );
        assert_eq!(
            reword("unknown field `x`, there are no fields", false),
            "unknown key `x`; no keys are allowed here"
        );
        // toml's wording for the tables of an enum (the camera forms).
        assert_eq!(
            reword("unexpected keys in table: ee, fovv, available keys: e, fov", true),
            "unknown keys `ee` (did you mean 'e'?), `fovv` (did you mean 'fov'?); the keys allowed here: e, fov"
        );
    }

    #[test]
    fn test02_numbers_are_words() {
        assert_eq!(
            reword("invalid type: string \"a\", expected f64", false),
            "invalid type: string \"a\", expected a number"
        );
        assert_eq!(
            reword("invalid value: integer `-1`, expected u32", false),
            "invalid value: integer `-1`, expected a whole number from 0 to 4294967295"
        );
        assert_eq!(reword("something else", false), "something else");
    }
}
