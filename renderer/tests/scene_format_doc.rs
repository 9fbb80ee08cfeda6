//! renderer/docs/scene-format.md documents every key the scene parser accepts. The keys
//! are read from the serde types in renderer/src/scene/format.rs (field names, `rename`,
//! `rename_all`, enum variants), and the values of the enums they use from the files that
//! define those enums. Each key must appear as `` `key` `` in the document's section for
//! its TOML table, and each enum value as `"value"` in the section of the key that takes
//! it, so a new field cannot be added without documenting it.

use std::collections::BTreeMap;

const FORMAT: &str = include_str!("../src/scene/format.rs");
const DOC: &str = include_str!("../docs/scene-format.md");

/// Where each type of format.rs is documented: (type or `Enum::Variant`, heading text).
const SECTIONS: &[(&str, &str)] = &[
    ("SceneDesc", "## Top level"),
    ("CameraDesc::View", "### `[camera.view]`"),
    ("WindowDesc", "### `[camera.view]`"),
    ("CameraDesc::LookAt", "### `[camera.look_at]`"),
    ("CameraDesc::Povray", "### `[camera.povray]`"),
    ("RenderDesc", "## `[render]`"),
    ("LightDesc", "## `[[lights]]`"),
    ("MaterialDesc", "## `[materials.NAME]`"),
    ("NodeDesc", "## Nodes"),
    ("NodeKind", "## Nodes"),
    ("TransformOp", "### Transform operations"),
    ("TransformOp::Rotate", "### Transform operations"),
    ("ShearDesc", "### Transform operations"),
];

/// Types whose variants are not keys or values of their own (an untagged choice of forms).
const FORMS: &[&str] = &["ScaleArg"];

struct Key {
    /// The TOML key (or value, for a unit enum).
    name: String,
    /// The Rust type of the field, for keys that take enum values.
    ty: String,
}

fn snake(s: &str) -> String {
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push('_');
        }
        out.extend(c.to_lowercase());
    }
    out
}

fn rename_rule(attrs: &str) -> Option<&'static str> {
    if attrs.contains("rename_all = \"snake_case\"") {
        Some("snake")
    } else if attrs.contains("rename_all = \"lowercase\"") {
        Some("lower")
    } else {
        assert!(
            !attrs.contains("rename_all"),
            "renderer/tests/scene_format_doc.rs does not know the rename_all rule in {attrs:?}: \
teach rename_rule and apply about it"
        );
        None
    }
}

/// Every `alias = "..."` in a field's attributes: other spellings the parser accepts.
fn aliases(attrs: &str) -> Vec<String> {
    attrs
        .split("alias = \"")
        .skip(1)
        .filter_map(|s| s.split('"').next())
        .map(str::to_string)
        .collect()
}

fn apply(rule: Option<&str>, name: &str) -> String {
    match rule {
        Some("snake") => snake(name),
        Some("lower") => name.to_lowercase(),
        _ => name.to_string(),
    }
}

fn explicit_rename(attrs: &str) -> Option<String> {
    let i = attrs.find("rename = \"")? + "rename = \"".len();
    Some(attrs[i..].split('"').next()?.to_string())
}

/// The items of a Rust source: (kind, name, container attributes, body lines).
fn items(src: &str) -> Vec<(&'static str, String, String, Vec<String>)> {
    let lines: Vec<&str> = src.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let kind = if l.starts_with("pub struct ") {
            "struct"
        } else if l.starts_with("pub enum ") {
            "enum"
        } else {
            continue;
        };
        let name = l
            .split_whitespace()
            .nth(2)
            .unwrap()
            .trim_end_matches('{')
            .to_string();
        let mut attrs = String::new();
        let mut k = i;
        // Attributes and doc comments above the item (a derive may span several lines).
        while k > 0 {
            let above = lines[k - 1];
            let t = above.trim();
            if t.is_empty()
                || above.starts_with('}')
                || above.starts_with("pub ")
                || above.starts_with("fn ")
                || above.starts_with("use ")
            {
                break;
            }
            k -= 1;
            attrs.insert_str(0, above);
        }
        let body: Vec<String> = lines[i + 1..]
            .iter()
            .take_while(|b| !b.starts_with('}'))
            .map(|b| b.to_string())
            .collect();
        out.push((kind, name, attrs, body));
    }
    out
}

/// Keys of a struct body, or of a struct variant's body (`indent` spaces deep).
fn fields(body: &[String], indent: usize, rule: Option<&str>) -> Vec<Key> {
    let pad = " ".repeat(indent);
    let mut keys = Vec::new();
    let mut attrs = String::new();
    for l in body {
        let Some(rest) = l.strip_prefix(&pad) else {
            continue;
        };
        if rest.starts_with(' ') {
            continue;
        }
        if rest.starts_with("#[") {
            attrs.push_str(rest);
            continue;
        }
        if rest.starts_with("///") {
            continue;
        }
        let rest = rest.trim_start_matches("pub ");
        if let Some((name, ty)) = rest.split_once(": ") {
            assert!(
                !attrs.contains("flatten"),
                "renderer/src/scene/format.rs: field `{name}` is #[serde(flatten)]: teach \
renderer/tests/scene_format_doc.rs to read the flattened type's keys into this section"
            );
            if !attrs.contains("serde(skip") {
                let ty = ty.trim_end_matches(',').to_string();
                keys.push(Key {
                    name: explicit_rename(&attrs).unwrap_or_else(|| apply(rule, name)),
                    ty: ty.clone(),
                });
                for a in aliases(&attrs) {
                    keys.push(Key {
                        name: a,
                        ty: ty.clone(),
                    });
                }
            }
        }
        attrs.clear();
    }
    keys
}

/// Variants of an enum body: (name as written in TOML, its struct-variant body if any).
fn variants(body: &[String], rule: Option<&str>) -> Vec<(String, String, Vec<String>)> {
    let mut out = Vec::new();
    let mut i = 0;
    let mut attrs = String::new();
    while i < body.len() {
        let l = &body[i];
        let t = l.trim_start();
        let depth = l.len() - t.len();
        if depth == 4 && t.starts_with("#[") {
            attrs.push_str(t);
        }
        if depth == 4 && t.chars().next().is_some_and(|c| c.is_uppercase()) {
            let raw: String = t.chars().take_while(|c| c.is_alphanumeric()).collect();
            let mut inner = Vec::new();
            if t.ends_with('{') {
                i += 1;
                while i < body.len() && !body[i].starts_with("    }") {
                    inner.push(body[i].clone());
                    i += 1;
                }
            }
            let toml = explicit_rename(&attrs).unwrap_or_else(|| apply(rule, &raw));
            for a in aliases(&attrs) {
                out.push((a, raw.clone(), Vec::new()));
            }
            out.push((toml, raw, inner));
            attrs.clear();
        }
        i += 1;
    }
    out
}

/// The text of the section under the heading containing `heading`, up to the next heading
/// of the same or a higher level.
fn section(heading: &str) -> &'static str {
    let start = DOC
        .lines()
        .position(|l| l.starts_with('#') && l.contains(heading))
        .unwrap_or_else(|| panic!("renderer/docs/scene-format.md has no heading `{heading}`"));
    let level = heading.chars().take_while(|c| *c == '#').count();
    let lines: Vec<&str> = DOC.lines().collect();
    let end = lines[start + 1..]
        .iter()
        .position(|l| {
            let h = l.chars().take_while(|c| *c == '#').count();
            h > 0 && h <= level && l.chars().nth(h) == Some(' ')
        })
        .map_or(lines.len(), |p| start + 1 + p);
    let from = lines[..start].iter().map(|l| l.len() + 1).sum::<usize>();
    let to = lines[..end]
        .iter()
        .map(|l| l.len() + 1)
        .sum::<usize>()
        .min(DOC.len());
    &DOC[from..to]
}

/// The values of an enum defined somewhere in renderer/src, as TOML strings.
fn enum_values(name: &str) -> Option<Vec<String>> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/src");
    let mut stack = vec![std::path::PathBuf::from(dir)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let src = std::fs::read_to_string(&p).unwrap();
            for (kind, n, attrs, body) in items(&src) {
                if kind == "enum" && n == name && attrs.contains("Deserialize") {
                    let rule = rename_rule(&attrs);
                    return Some(variants(&body, rule).into_iter().map(|v| v.0).collect());
                }
            }
        }
    }
    None
}

/// Every (section heading, key) pair and every (section, key, value) the parser accepts.
fn accepted() -> (Vec<(String, String, String)>, Vec<String>) {
    let sections: BTreeMap<&str, &str> = SECTIONS.iter().copied().collect();
    let mut keys = Vec::new(); // (heading, what, key)
    let mut problems = Vec::new();
    let mut missing_forms = Vec::new();
    let mut place = |owner: &str, key: &Key, keys: &mut Vec<(String, String, String)>| {
        match sections.get(owner) {
            Some(h) => {
                keys.push((h.to_string(), owner.to_string(), key.name.clone()));
                let ty = key.ty.trim_start_matches("Option<").trim_end_matches('>');
                let last = ty.rsplit("::").next().unwrap_or(ty);
                if !last.is_empty() && last.chars().next().unwrap().is_uppercase() && !["Spanned<String", "String", "V3", "Vec<Spanned<TransformOp", "Vec<Spanned<NodeDesc"].iter().any(|x| ty.starts_with(x)) {
                    if let Some(values) = enum_values(last) {
                        for v in values {
                            keys.push((h.to_string(), format!("{owner}.{}", key.name), format!("\"{v}\"")));
                        }
                    }
                }
            }
            None => problems.push(format!(
                "renderer/src/scene/format.rs: `{owner}` (key `{}`) has no section in renderer/docs/scene-format.md; \
document it and map it in SECTIONS of renderer/tests/scene_format_doc.rs",
                key.name
            )),
        }
    };
    for (kind, name, attrs, body) in items(FORMAT) {
        if !attrs.contains("Deserialize") || FORMS.contains(&name.as_str()) {
            continue;
        }
        let rule = rename_rule(&attrs);
        if kind == "struct" {
            for k in fields(&body, 4, rule) {
                place(&name, &k, &mut keys);
            }
            continue;
        }
        for (toml, raw, inner) in variants(&body, rule) {
            let owner = format!("{name}::{raw}");
            if name == "CameraDesc" {
                // A camera form is a table of its own: its heading names it.
                let heading = format!("`[camera.{toml}]`");
                if !DOC
                    .lines()
                    .any(|l| l.starts_with('#') && l.contains(&heading))
                {
                    missing_forms.push(format!("renderer/docs/scene-format.md has no section {heading} for the camera form `{toml}`"));
                }
            } else {
                place(
                    &name,
                    &Key {
                        name: toml.clone(),
                        ty: String::new(),
                    },
                    &mut keys,
                );
            }
            for k in fields(&inner, 8, None) {
                place(&owner, &k, &mut keys);
            }
        }
    }
    problems.extend(missing_forms);
    (keys, problems)
}

#[test]
fn test01_every_accepted_key_is_documented_in_its_section() {
    let (keys, mut problems) = accepted();
    assert!(
        keys.len() > 60,
        "the parser reading format.rs found only {} keys",
        keys.len()
    );
    for (heading, owner, key) in &keys {
        let text = section(heading);
        let shown = if key.starts_with('"') {
            // A value: "value" or `value`.
            text.contains(key.as_str()) || text.contains(&format!("`{}`", key.trim_matches('"')))
        } else {
            text.contains(&format!("`{key}`"))
        };
        if !shown {
            problems.push(format!(
                "{owner}: {key} is accepted by the parser but not documented under the heading {heading:?} of renderer/docs/scene-format.md"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn test02_the_reader_finds_the_keys_it_must() {
    // If the reader of format.rs broke, the first test could pass vacuously.
    let (keys, _) = accepted();
    let has = |h: &str, k: &str| keys.iter().any(|(hh, _, kk)| hh.contains(h) && kk == k);
    for (h, k) in [
        ("[render]", "rr_depth"),
        ("[render]", "\"path\""),
        ("[render]", "\"sobol\""),
        ("[[lights]]", "type"),
        ("[[lights]]", "\"directional\""),
        ("[[lights]]", "direction"),
        ("[materials.NAME]", "model"),
        ("[materials.NAME]", "\"dielectric\""),
        ("[materials.NAME]", "radiance"),
        ("Nodes", "type"),
        ("Nodes", "instance"),
        ("[camera.look_at]", "fov_axis"),
        ("[camera.look_at]", "\"vertical\""),
        ("[camera.view]", "left"),
        ("Transform", "degrees"),
        ("Transform", "zy"),
        ("Transform", "matrix"),
    ] {
        assert!(
            has(h, k),
            "the reader of format.rs did not find {k} under {h}"
        );
    }
}
