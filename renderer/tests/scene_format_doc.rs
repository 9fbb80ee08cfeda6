//! renderer/docs/scene-format.md documents every key the scene parser accepts.
//!
//! The keys are derived from the source, not listed by hand: the test reads the serde types
//! of renderer/src/scene/format.rs (and the types they use, anywhere in renderer/src),
//! starting at `SceneDesc`, and follows field types into their TOML tables. It honours
//! `rename`, `rename_all`, `alias`, `skip`, `skip_deserializing`, `flatten`, `untagged` and
//! `tag`; an enum of unit variants gives the string values of the key that takes it, an
//! externally tagged enum with data gives keys (`[camera.view]`, `{ rotate = … }`). A serde
//! attribute it does not understand is an error, so it cannot silently read wrong keys.
//!
//! Each key must have a row in a table of the document's section for its type (SECTIONS
//! below): a row whose first cell holds `` `key` ``, in a table with `type`, `default` and
//! `meaning` columns, none of them empty. Each enum value must appear in that row as
//! `"value"` or `` `value` ``.

use std::collections::{BTreeMap, BTreeSet};

const DOC_PATH: &str = "renderer/docs/scene-format.md";
const FORMAT_PATH: &str = "renderer/src/scene/format.rs";
const DOC: &str = include_str!("../docs/scene-format.md");
const ROOT: &str = "SceneDesc";

/// Where the keys of each Rust type (or struct variant `Enum::Variant`) are documented:
/// the document's heading, matched by prefix. A section ends at the next heading.
const SECTIONS: &[(&str, &str)] = &[
    ("SceneDesc", "## Top level"),
    ("CameraDesc", "## `camera`"),
    ("CameraDesc::View", "### `[camera.view]`"),
    ("WindowDesc", "### `[camera.view]`"),
    ("CameraDesc::LookAt", "### `[camera.look_at]`"),
    ("CameraDesc::Povray", "### `[camera.povray]`"),
    ("RenderDesc", "## `[render]`"),
    ("LightDesc", "## `[[lights]]`"),
    ("MaterialDesc", "## `[materials.NAME]`"),
    ("NodeDesc", "## Nodes"),
    ("TransformOp", "### Transform operations"),
    ("TransformOp::Rotate", "### Transform operations"),
    ("ShearDesc", "### Transform operations"),
];

// ---------------------------------------------------------------- reading Rust source

#[derive(Clone, Debug, Default)]
struct Serde(Vec<(String, Option<String>)>);

impl Serde {
    fn has(&self, k: &str) -> bool {
        self.0.iter().any(|(kk, _)| kk == k)
    }
    fn get(&self, k: &str) -> Option<&str> {
        self.0
            .iter()
            .find(|(kk, _)| kk == k)
            .and_then(|(_, v)| v.as_deref())
    }
    fn all(&self, k: &str) -> Vec<String> {
        let vals = self.0.iter().filter(|(kk, _)| kk == k);
        vals.filter_map(|(_, v)| v.clone()).collect()
    }
    /// Attribute names outside `known`.
    fn unknown(&self, known: &[&str]) -> Vec<String> {
        let names = self.0.iter().map(|(k, _)| k);
        names
            .filter(|k| !known.contains(&k.as_str()))
            .cloned()
            .collect()
    }
}

#[derive(Clone, Debug)]
struct Field {
    name: String,
    ty: String,
    serde: Serde,
}

#[derive(Clone, Debug)]
enum Shape {
    Unit,
    Tuple(Vec<String>),
    Struct(Vec<Field>),
}

#[derive(Clone, Debug)]
struct Variant {
    name: String,
    serde: Serde,
    shape: Shape,
}

#[derive(Clone, Debug)]
struct Item {
    name: String,
    file: String,
    serde: Serde,
    /// `None` for an enum.
    fields: Option<Vec<Field>>,
    variants: Vec<Variant>,
}

/// Drops `//` comment lines (doc comments hold braces and quotes).
fn strip_comments(src: &str) -> String {
    let lines = src.lines().filter(|l| !l.trim_start().starts_with("//"));
    lines.collect::<Vec<_>>().join("\n")
}

/// Index of the bracket closing the one at `open`, skipping string and char literals.
fn matching(s: &[u8], open: usize) -> usize {
    let (o, c) = (
        s[open],
        match s[open] {
            b'{' => b'}',
            b'[' => b']',
            b'(' => b')',
            _ => b'>',
        },
    );
    let mut depth = 0;
    let mut i = open;
    while i < s.len() {
        match s[i] {
            b'"' => {
                i += 1;
                while i < s.len() && s[i] != b'"' {
                    i += if s[i] == b'\\' { 2 } else { 1 };
                }
            }
            b'\'' if i + 2 < s.len() && (s[i + 2] == b'\'' || s[i + 1] == b'\\') => {
                i += 2;
                while i < s.len() && s[i] != b'\'' {
                    i += 1;
                }
            }
            b if b == o => depth += 1,
            b if b == c => {
                depth -= 1;
                if depth == 0 {
                    return i;
                }
            }
            _ => {}
        }
        i += 1;
    }
    s.len()
}

/// Splits at commas outside brackets.
fn split_top(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut depth = 0i32;
    let mut cur = String::new();
    let mut in_str = false;
    let mut prev = ' ';
    for ch in s.chars() {
        if in_str {
            in_str = !(ch == '"' && prev != '\\');
        } else {
            match ch {
                '"' => in_str = true,
                '(' | '[' | '{' | '<' => depth += 1,
                ')' | ']' | '}' => depth -= 1,
                '>' if prev != '-' => depth -= 1,
                ',' if depth == 0 => {
                    out.push(std::mem::take(&mut cur));
                    prev = ch;
                    continue;
                }
                _ => {}
            }
        }
        cur.push(ch);
        prev = ch;
    }
    out.push(cur);
    out.into_iter()
        .map(|x| x.trim().to_string())
        .filter(|x| !x.is_empty())
        .collect()
}

/// Leading `#[...]` attributes of `s` and the rest.
fn take_attrs(s: &str) -> (Vec<String>, &str) {
    let mut attrs = Vec::new();
    let mut rest = s.trim_start();
    while rest.starts_with("#[") {
        let end = matching(rest.as_bytes(), 1);
        attrs.push(rest[2..end].trim().to_string());
        rest = rest[end + 1..].trim_start();
    }
    (attrs, rest)
}

fn unquote(s: &str) -> String {
    s.trim().trim_matches('"').to_string()
}

/// The `serde(...)` entries of some attributes: `name`, `name = "v"`, or
/// `name(deserialize = "v", ...)` (read as `name = "v"`).
fn serde_of(attrs: &[String]) -> Serde {
    let mut out = Vec::new();
    for a in attrs {
        let Some(inner) = a.strip_prefix("serde") else {
            continue;
        };
        let inner = inner.trim();
        let inner = &inner[1..inner.len() - 1];
        for part in split_top(inner) {
            if let Some(p) = part.find('(').filter(|p| !part[..*p].contains('=')) {
                let args = &part[p + 1..part.len() - 1];
                let de = split_top(args).into_iter().find_map(|x| {
                    x.split_once('=')
                        .filter(|(k, _)| k.trim() == "deserialize")
                        .map(|(_, v)| unquote(v))
                });
                out.push((part[..p].trim().to_string(), de));
            } else if let Some((k, v)) = part.split_once('=') {
                out.push((k.trim().to_string(), Some(unquote(v))));
            } else {
                out.push((part.trim().to_string(), None));
            }
        }
    }
    Serde(out)
}

fn fields_of(body: &str) -> Vec<Field> {
    let mut out = Vec::new();
    for seg in split_top(body) {
        let (attrs, rest) = take_attrs(&seg);
        let rest = rest
            .trim_start_matches("pub(crate)")
            .trim_start_matches("pub")
            .trim();
        if let Some((name, ty)) = rest.split_once(':') {
            out.push(Field {
                name: name.trim().trim_start_matches("r#").to_string(),
                ty: ty.split_whitespace().collect(),
                serde: serde_of(&attrs),
            });
        }
    }
    out
}

fn variants_of(body: &str) -> Vec<Variant> {
    let mut out = Vec::new();
    for seg in split_top(body) {
        let (attrs, rest) = take_attrs(&seg);
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let after = rest[name.len()..].trim();
        let shape = if after.starts_with('{') {
            Shape::Struct(fields_of(&after[1..after.len() - 1]))
        } else if after.starts_with('(') {
            let inner = &after[1..after.len() - 1];
            Shape::Tuple(
                split_top(inner)
                    .into_iter()
                    .map(|t| t.split_whitespace().collect())
                    .collect(),
            )
        } else {
            Shape::Unit
        };
        out.push(Variant {
            name,
            serde: serde_of(&attrs),
            shape,
        });
    }
    out
}

/// The structs and enums of a source file that derive `Deserialize`.
fn items_of(file: &str, src: &str) -> Vec<Item> {
    let text = strip_comments(src);
    let s = text.as_bytes();
    let mut out = Vec::new();
    let mut attrs: Vec<String> = Vec::new();
    let mut i = 0;
    let word_at = |i: usize| -> String {
        text[i..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    while i < s.len() {
        if s[i].is_ascii_whitespace() {
            i += 1;
            continue;
        }
        if text[i..].starts_with("#[") || text[i..].starts_with("#![") {
            let open = i + text[i..].find('[').unwrap();
            let end = matching(s, open);
            attrs.push(text[open + 1..end].trim().to_string());
            i = end + 1;
            continue;
        }
        let w = word_at(i);
        if w == "pub" {
            i += 3;
            if text[i..].starts_with('(') {
                i = matching(s, i) + 1;
            }
            continue;
        }
        // Any other item: up to its `;` or the end of its first `{...}`.
        let stop = text[i..].find([';', '{']).map_or(s.len(), |p| i + p);
        let end = if stop < s.len() && s[stop] == b'{' {
            matching(s, stop)
        } else {
            stop
        };
        if w == "struct" || w == "enum" {
            let derives = attrs
                .iter()
                .any(|a| a.starts_with("derive") && a.contains("Deserialize"));
            let name = word_at(i + w.len() + 1);
            if derives && stop < s.len() && s[stop] == b'{' {
                let body = &text[stop + 1..end];
                out.push(Item {
                    name,
                    file: file.to_string(),
                    serde: serde_of(&attrs),
                    fields: (w == "struct").then(|| fields_of(body)),
                    variants: if w == "enum" {
                        variants_of(body)
                    } else {
                        Vec::new()
                    },
                });
            }
        }
        attrs.clear();
        i = end + 1;
    }
    out
}

/// Every `Deserialize` struct and enum of renderer/src, by name.
fn source_items() -> BTreeMap<String, Vec<Item>> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut stack = vec![root.join("src")];
    let mut files = Vec::new();
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    files.sort();
    let mut map: BTreeMap<String, Vec<Item>> = BTreeMap::new();
    for p in files {
        let rel = format!("renderer/{}", p.strip_prefix(root).unwrap().display());
        for it in items_of(&rel, &std::fs::read_to_string(&p).unwrap()) {
            map.entry(it.name.clone()).or_default().push(it);
        }
    }
    map
}

// ---------------------------------------------------------------- serde's naming rules

fn words_of_pascal(s: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for c in s.chars() {
        if c.is_uppercase() || out.is_empty() {
            out.push(String::new());
        }
        out.last_mut().unwrap().extend(c.to_lowercase());
    }
    out
}

/// The TOML name of a Rust name under a `rename_all` rule; `variant` names are PascalCase,
/// field names snake_case.
fn rename(rule: Option<&str>, name: &str, variant: bool) -> Result<String, String> {
    let words: Vec<String> = if variant {
        words_of_pascal(name)
    } else {
        name.split('_').map(str::to_string).collect()
    };
    let cap = |w: &String| {
        let mut c = w.chars();
        c.next()
            .map(|f| f.to_uppercase().chain(c).collect::<String>())
            .unwrap_or_default()
    };
    let pascal: String = words.iter().map(cap).collect();
    Ok(match rule {
        None => name.to_string(),
        Some("lowercase") => {
            if variant {
                name.to_lowercase()
            } else {
                name.to_string()
            }
        }
        Some("UPPERCASE") => name.to_uppercase(),
        Some("PascalCase") => pascal,
        Some("camelCase") => {
            let mut c = pascal.chars();
            c.next()
                .map(|f| f.to_lowercase().chain(c).collect())
                .unwrap_or_default()
        }
        Some("snake_case") => words.join("_"),
        Some("SCREAMING_SNAKE_CASE") => words.join("_").to_uppercase(),
        Some("kebab-case") => words.join("-"),
        Some("SCREAMING-KEBAB-CASE") => words.join("-").to_uppercase(),
        Some(r) => return Err(format!("unknown rename_all rule {r:?}")),
    })
}

// ---------------------------------------------------------------- the accepted keys

/// One key the parser accepts.
#[derive(Clone, Debug)]
struct Key {
    /// The Rust type (or `Enum::Variant`) that holds it: it picks the doc section.
    owner: String,
    /// The TOML table it is written in, e.g. `[[lights]]`.
    table: String,
    /// The key.
    key: String,
    /// For a key that takes an enum of unit variants: the accepted strings.
    values: Vec<String>,
}

const CONTAINER_ATTRS: &[&str] = &[
    "deny_unknown_fields",
    "rename_all",
    "rename_all_fields",
    "untagged",
    "tag",
    "default",
    "bound",
    "expecting",
    "crate",
];
const FIELD_ATTRS: &[&str] = &[
    "rename",
    "alias",
    "default",
    "skip",
    "skip_deserializing",
    "skip_serializing",
    "skip_serializing_if",
    "flatten",
    "deserialize_with",
    "serialize_with",
    "with",
    "borrow",
    "bound",
];
const VARIANT_ATTRS: &[&str] = &[
    "rename",
    "alias",
    "skip",
    "skip_deserializing",
    "skip_serializing",
    "rename_all",
    "deserialize_with",
    "serialize_with",
    "with",
    "borrow",
    "bound",
];

struct Reader<'a> {
    items: &'a BTreeMap<String, Vec<Item>>,
    keys: Vec<Key>,
    problems: Vec<String>,
    seen: BTreeSet<String>,
}

impl Reader<'_> {
    /// The one item of this name; a problem if it is defined twice.
    fn item(&mut self, name: &str) -> Option<Item> {
        let found = self.items.get(name)?;
        let fmt: Vec<&Item> = found.iter().filter(|i| i.file == FORMAT_PATH).collect();
        match (fmt.as_slice(), found.as_slice()) {
            ([one], _) => Some((*one).clone()),
            ([], [one]) => Some(one.clone()),
            _ => {
                let files: Vec<&str> = found.iter().map(|i| i.file.as_str()).collect();
                self.problems.push(format!(
                    "`{name}` is defined in {files:?}; renderer/tests/scene_format_doc.rs cannot tell which one the scene parser uses"
                ));
                None
            }
        }
    }

    fn check_attrs(&mut self, what: &str, serde: &Serde, known: &[&str]) {
        for a in serde.unknown(known) {
            self.problems.push(format!(
                "{what}: renderer/tests/scene_format_doc.rs does not understand #[serde({a})]; teach it what keys that accepts"
            ));
        }
    }

    /// The serde types named in a Rust type, innermost last, and whether the outermost
    /// container (under `Option`/`Spanned`/`Box`) is a sequence or a map.
    fn inner_type(&mut self, ty: &str) -> (Option<String>, &'static str) {
        let idents: Vec<&str> = ty
            .split(|c: char| !(c.is_alphanumeric() || c == '_'))
            .filter(|w| !w.is_empty())
            .collect();
        let outer = idents
            .iter()
            .find(|w| !["Option", "Spanned", "Box", "crate", "super", "self"].contains(w))
            .copied()
            .unwrap_or("");
        let suffix = match outer {
            "Vec" => "[]",
            "BTreeMap" | "HashMap" | "IndexMap" => ".NAME",
            _ => "",
        };
        let named: Vec<&str> = idents
            .iter()
            .filter(|w| self.items.contains_key(**w))
            .copied()
            .collect();
        (named.last().map(|s| s.to_string()), suffix)
    }

    /// The keys of a struct written in `table`; `owner` overrides the section (flatten).
    fn struct_keys(&mut self, item: &Item, table: &str, owner: &str) {
        let what = format!("{} ({})", item.name, item.file);
        self.check_attrs(&what, &item.serde.clone(), CONTAINER_ATTRS);
        let rule = item.serde.get("rename_all").map(str::to_string);
        for f in item.fields.clone().unwrap_or_default() {
            self.field(
                &f,
                rule.as_deref(),
                table,
                owner,
                &format!("{}.{}", item.name, f.name),
            );
        }
    }

    fn field(&mut self, f: &Field, rule: Option<&str>, table: &str, owner: &str, what: &str) {
        self.check_attrs(what, &f.serde, FIELD_ATTRS);
        if f.serde.has("skip") || f.serde.has("skip_deserializing") {
            return;
        }
        let (inner, suffix) = self.inner_type(&f.ty);
        let inner = inner.and_then(|n| self.item(&n));
        if f.serde.has("flatten") {
            match inner {
                Some(it) if it.fields.is_some() => self.struct_keys(&it, table, owner),
                _ => self.problems.push(format!(
                    "{what}: renderer/tests/scene_format_doc.rs reads #[serde(flatten)] only on a struct field"
                )),
            }
            return;
        }
        let name = match f.serde.get("rename") {
            Some(r) => r.to_string(),
            None => rename(rule, &f.name, false).unwrap_or_else(|e| {
                self.problems.push(format!("{what}: {e}"));
                f.name.clone()
            }),
        };
        let sub = if table.is_empty() {
            format!("{name}{suffix}")
        } else {
            format!("{table}.{name}{suffix}")
        };
        let mut values = Vec::new();
        if let Some(it) = inner {
            if it.fields.is_none() {
                values = self.enum_keys(&it, &sub);
            } else if self.seen.insert(it.name.clone()) {
                // Read once: a recursive type (a node's children) ends here.
                self.struct_keys(&it, &sub, &it.name.clone());
            }
        }
        let mut names = vec![name];
        names.extend(f.serde.all("alias"));
        for key in names {
            self.keys.push(Key {
                owner: owner.to_string(),
                table: table.to_string(),
                key,
                values: values.clone(),
            });
        }
    }

    /// Reads an enum used as the type of a key written in `table`; returns the strings
    /// the key takes (its unit variants), and records the keys its other variants add.
    fn enum_keys(&mut self, item: &Item, table: &str) -> Vec<String> {
        let what = format!("{} ({})", item.name, item.file);
        self.check_attrs(&what, &item.serde, CONTAINER_ATTRS);
        let rule = item.serde.get("rename_all");
        let field_rule = item.serde.get("rename_all_fields").map(str::to_string);
        let untagged = item.serde.has("untagged");
        let tag = item.serde.get("tag").map(str::to_string);
        let mut values = Vec::new();
        for v in &item.variants {
            let vwhat = format!("{}::{}", item.name, v.name);
            self.check_attrs(&vwhat, &v.serde, VARIANT_ATTRS);
            if v.serde.has("skip") || v.serde.has("skip_deserializing") {
                continue;
            }
            let mut names = vec![match v.serde.get("rename") {
                Some(r) => r.to_string(),
                None => rename(rule, &v.name, true).unwrap_or_else(|e| {
                    self.problems.push(format!("{what}: {e}"));
                    v.name.clone()
                }),
            }];
            names.extend(v.serde.all("alias"));
            let vrule = v
                .serde
                .get("rename_all")
                .map(str::to_string)
                .or(field_rule.clone());
            // Where the variant's own fields are written, and who documents them.
            let (ftable, fowner) = if untagged || tag.is_some() {
                (table.to_string(), vwhat.clone())
            } else {
                (format!("{table}.{}", names[0]), vwhat.clone())
            };
            if untagged {
                // The variant is a form of the value, not a key or a string of its own.
            } else if tag.is_some() || matches!(v.shape, Shape::Unit) {
                values.extend(names.iter().cloned());
            } else {
                for n in &names {
                    self.keys.push(Key {
                        owner: item.name.clone(),
                        table: table.to_string(),
                        key: n.clone(),
                        values: Vec::new(),
                    });
                }
            }
            match &v.shape {
                Shape::Unit => {}
                Shape::Struct(fields) => {
                    for f in fields {
                        let fw = format!("{vwhat}.{}", f.name);
                        self.field(f, vrule.as_deref(), &ftable, &fowner, &fw);
                    }
                }
                Shape::Tuple(tys) => {
                    for ty in tys {
                        let (inner, _) = self.inner_type(ty);
                        let Some(it) = inner.and_then(|n| self.item(&n)) else {
                            continue;
                        };
                        if it.fields.is_none() {
                            // A nested enum: its keys are read, its strings not checked.
                            self.enum_keys(&it, &ftable);
                        } else if self.seen.insert(it.name.clone()) {
                            self.struct_keys(&it, &ftable, &it.name.clone());
                        }
                    }
                }
            }
        }
        if let Some(t) = tag {
            // Internally tagged: the tag is a key of the table, the variants its values.
            self.keys.push(Key {
                owner: item.name.clone(),
                table: table.to_string(),
                key: t,
                values: values.clone(),
            });
            return Vec::new();
        }
        values
    }
}

/// Every key the parser accepts, starting at `root`, and the problems met reading them.
fn accepted(items: &BTreeMap<String, Vec<Item>>, root: &str) -> (Vec<Key>, Vec<String>) {
    let mut r = Reader {
        items,
        keys: Vec::new(),
        problems: Vec::new(),
        seen: BTreeSet::from([root.to_string()]),
    };
    match r.item(root) {
        Some(it) => r.struct_keys(&it, "", root),
        None => r.problems.push(format!(
            "{FORMAT_PATH} has no `#[derive(Deserialize)] struct {root}`"
        )),
    }
    (r.keys, r.problems)
}

// ---------------------------------------------------------------- reading the document

/// The lines from the heading that starts with `heading` to the next heading.
fn section<'a>(doc: &'a str, heading: &str) -> Option<Vec<&'a str>> {
    let lines: Vec<&str> = doc.lines().collect();
    let start = lines.iter().position(|l| l.starts_with(heading))?;
    let rest = &lines[start + 1..];
    let end = rest
        .iter()
        .position(|l| l.starts_with('#'))
        .unwrap_or(rest.len());
    Some(rest[..end].to_vec())
}

fn cells(line: &str) -> Vec<String> {
    let t = line.trim().trim_start_matches('|').trim_end_matches('|');
    t.split('|').map(|c| c.trim().to_string()).collect()
}

/// The tables of a section: (header cells, rows of cells).
fn tables(lines: &[&str]) -> Vec<(Vec<String>, Vec<Vec<String>>)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < lines.len() {
        let sep = lines[i + 1].trim();
        if lines[i].trim_start().starts_with('|') && sep.starts_with("|") && sep.contains("---") {
            let header = cells(lines[i]);
            let mut rows = Vec::new();
            i += 2;
            while i < lines.len() && lines[i].trim_start().starts_with('|') {
                rows.push(cells(lines[i]));
                i += 1;
            }
            out.push((header, rows));
        } else {
            i += 1;
        }
    }
    out
}

/// What is wrong with `doc` for these keys: one line per problem.
fn check(doc: &str, keys: &[Key]) -> Vec<String> {
    let sections: BTreeMap<&str, &str> = SECTIONS.iter().copied().collect();
    let mut problems = Vec::new();
    for k in keys {
        let table = if k.table.is_empty() {
            "the top level".to_string()
        } else if let Some(array) = k.table.strip_suffix("[]") {
            format!("TOML table `[[{array}]]`")
        } else {
            format!("TOML table `[{}]`", k.table)
        };
        let what = format!("key `{}` of {table} ({} in the source)", k.key, k.owner);
        let Some(heading) = sections.get(k.owner.as_str()) else {
            problems.push(format!(
                "{what}: `{}` has no entry in SECTIONS of renderer/tests/scene_format_doc.rs; document it in {DOC_PATH} and add the entry",
                k.owner
            ));
            continue;
        };
        let Some(lines) = section(doc, heading) else {
            problems.push(format!(
                "{what}: {DOC_PATH} has no heading starting with {heading:?}"
            ));
            continue;
        };
        let code = format!("`{}`", k.key);
        let found = tables(&lines).into_iter().find_map(|(header, rows)| {
            let row = rows.into_iter().find(|r| r[0].contains(&code))?;
            Some((header, row))
        });
        let Some((header, row)) = found else {
            problems.push(format!(
                "{what} is accepted by the parser but not documented: {DOC_PATH}, section {heading:?}, has no table row whose first cell holds {code}"
            ));
            continue;
        };
        for col in ["type", "default", "meaning"] {
            let idx = header
                .iter()
                .position(|h| h.to_lowercase().starts_with(col));
            match idx {
                None => problems.push(format!(
                    "{what}: its table in section {heading:?} of {DOC_PATH} has no `{col}` column (header {header:?})"
                )),
                Some(i) if row.get(i).is_none_or(|c| c.is_empty()) => problems.push(format!(
                    "{what}: its row in section {heading:?} of {DOC_PATH} has an empty `{col}` cell"
                )),
                Some(_) => {}
            }
        }
        let text = row.join(" | ");
        for v in &k.values {
            if !text.contains(&format!("\"{v}\"")) && !text.contains(&format!("`{v}`")) {
                problems.push(format!(
                    "{what} accepts the value \"{v}\", but its row in section {heading:?} of {DOC_PATH} does not name it (as \"{v}\" or `{v}`)"
                ));
            }
        }
    }
    problems
}

fn has(keys: &[Key], table: &str, key: &str) -> bool {
    keys.iter().any(|k| k.table == table && k.key == key)
}

// ---------------------------------------------------------------- tests

#[test]
fn test01_every_accepted_key_is_documented_in_its_section() {
    let items = source_items();
    let (keys, mut problems) = accepted(&items, ROOT);
    problems.extend(check(DOC, &keys));
    assert!(
        problems.is_empty(),
        "{} problem(s) between {FORMAT_PATH} and {DOC_PATH}:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn test02_the_reader_finds_the_keys_it_must() {
    // If the reader of format.rs broke, the first test could pass vacuously.
    let items = source_items();
    let (keys, _) = accepted(&items, ROOT);
    assert!(
        keys.len() > 60,
        "the reader of {FORMAT_PATH} found only {} keys",
        keys.len()
    );
    for (table, key) in [
        ("", "camera"),
        ("camera", "look_at"),
        ("camera.view", "window"),
        ("camera.view.window", "left"),
        ("camera.look_at", "fov_axis"),
        ("render", "integrator"),
        ("render", "rr_depth"),
        ("render", "sampler"),
        ("lights[]", "type"),
        ("lights[]", "direction"),
        ("materials.NAME", "model"),
        ("materials.NAME", "radiance"),
        ("defs.NAME", "type"),
        ("defs.NAME", "children"),
        ("defs.NAME.transform[]", "matrix"),
        ("defs.NAME.transform[].rotate", "degrees"),
        ("defs.NAME.transform[].shear", "zy"),
    ] {
        assert!(
            has(&keys, table, key),
            "the reader of {FORMAT_PATH} did not find `{key}` in table `{table}`"
        );
    }
    let values = |table: &str, key: &str| {
        let k = keys
            .iter()
            .find(|k| k.table == table && k.key == key)
            .unwrap();
        k.values.clone()
    };
    assert_eq!(
        values("render", "integrator"),
        ["classic", "direct", "path"]
    );
    assert!(values("render", "sampler").contains(&"sobol".to_string()));
    assert!(values("lights[]", "type").contains(&"directional".to_string()));
    assert!(values("materials.NAME", "model").contains(&"dielectric".to_string()));
    assert!(values("defs.NAME", "type").contains(&"instance".to_string()));
    assert_eq!(
        values("camera.look_at", "fov_axis"),
        ["horizontal", "vertical"]
    );
    // `scale` takes an untagged choice of forms: no values, no keys of its own.
    assert!(values("defs.NAME.transform[]", "scale").is_empty());
}

#[test]
fn test03_a_missing_row_or_value_fails_naming_key_and_table() {
    let items = source_items();
    let (keys, _) = accepted(&items, ROOT);
    let without = |needle: &str| -> String {
        let kept = DOC.lines().filter(|l| !l.starts_with(needle));
        kept.collect::<Vec<_>>().join("\n")
    };
    let p = check(&without("| `rr_depth` |"), &keys);
    assert!(
        p.len() == 1 && p[0].contains("`rr_depth`") && p[0].contains("`[render]`") && p[0].contains("RenderDesc"),
        "removing the rr_depth row should give one problem naming `rr_depth`, table `[render]` and RenderDesc, got {p:#?}"
    );
    let p = check(&DOC.replace("\"sobol\"", "\"halton\""), &keys);
    assert!(
        p.len() == 1 && p[0].contains("\"sobol\"") && p[0].contains("`sampler`"),
        "a sampler row without \"sobol\" should give one problem naming it, got {p:#?}"
    );
    let p = check(
        &DOC.replace(
            "| key | type | default | meaning |",
            "| key | kind | default | meaning |",
        ),
        &keys,
    );
    assert!(
        !p.is_empty() && p.iter().all(|x| x.contains("no `type` column")),
        "tables without a type column should be reported, got {p:#?}"
    );
}

#[test]
fn test04_the_reader_honours_serde_attributes() {
    let src = r#"
/// Doc comments { with braces } are ignored.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Root {
    pub plain_key: f64,
    #[serde(rename = "type", default)]
    pub kind: Kind,
    #[serde(alias = "colour", alias = "tint")]
    pub color: V3,
    #[serde(skip)]
    pub cache: u32,
    #[serde(skip_deserializing)]
    pub derived: u32,
    #[serde(flatten)]
    pub extra: Extra,
    #[serde(rename(serialize = "out", deserialize = "in"))]
    pub io: u32,
    pub parts: Vec<Spanned<Part>>,
    pub shape: Shape,
}
#[derive(Deserialize, Default)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
pub enum Kind {
    #[default]
    PointLight,
    #[serde(rename = "sun")]
    Directional,
    #[serde(skip)]
    Hidden,
}
#[derive(Deserialize)]
pub struct Extra {
    pub flat_one: u32,
}
#[derive(Deserialize)]
#[serde(tag = "model", rename_all = "lowercase")]
pub enum Part {
    Glass { ior: f64 },
    Metal,
}
#[derive(Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    BigBox { half_size: f64 },
    Ball(Ball),
}
#[derive(Deserialize)]
pub struct Ball {
    pub radius: f64,
}
pub struct NotSerde {
    pub nothing: u32,
}
"#;
    let mut items: BTreeMap<String, Vec<Item>> = BTreeMap::new();
    for it in items_of(FORMAT_PATH, src) {
        items.entry(it.name.clone()).or_default().push(it);
    }
    let (keys, problems) = accepted(&items, "Root");
    assert!(problems.is_empty(), "{problems:#?}");
    let mut got: Vec<String> = keys
        .iter()
        .map(|k| format!("{}|{}|{}|{}", k.owner, k.table, k.key, k.values.join(",")))
        .collect();
    got.sort();
    let mut want = vec![
        "Root||plain-key|",
        "Root||type|POINT_LIGHT,sun",
        "Root||color|",
        "Root||colour|",
        "Root||tint|",
        "Root||flat_one|",
        "Root||in|",
        "Root||parts|",
        "Part::Glass|parts[]|ior|",
        "Part|parts[]|model|glass,metal",
        "Root||shape|",
        "Shape|shape|big_box|",
        "Shape|shape|ball|",
        "Shape::BigBox|shape.big_box|half_size|",
        "Ball|shape.ball|radius|",
    ];
    want.sort();
    assert_eq!(got, want, "keys read from the sample source");

    // An attribute the reader does not know is an error, not a silent guess.
    let odd = src.replace("#[serde(flatten)]", "#[serde(with_magic)]");
    let mut items: BTreeMap<String, Vec<Item>> = BTreeMap::new();
    for it in items_of(FORMAT_PATH, &odd) {
        items.entry(it.name.clone()).or_default().push(it);
    }
    let (_, problems) = accepted(&items, "Root");
    assert!(
        problems
            .iter()
            .any(|p| p.contains("with_magic") && p.contains("Root.extra")),
        "an unknown serde attribute should be reported, got {problems:#?}"
    );
}
