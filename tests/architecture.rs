//! The architecture invariants that code can check: no module of the renderer or the
//! conformance crate imports a module that imports it back (directly or through others),
//! and the renderer never depends on the conformance crate.
//!
//! Modules are found as the compiler finds them: from `lib.rs`, each `mod x;` declares a
//! child whose file is `x.rs` or `x/mod.rs` beside (or, from a non-`mod.rs` file, under)
//! its parent's, or the file a `#[path = "…"]` names, relative to the declaring file's
//! folder; the child's name is its module path (`physical::light_paths`), whatever its
//! file is called. Edges are read from the source: every `crate::a::b`, `self::x`,
//! `super::x` (from the real parent, and from inside an inline `mod tests { … }` the file's
//! own module) and bare `child::x` path (a child the module declares) outside comments and
//! strings, resolved to the longest module prefix (a re-export of the crate root is
//! followed to the module it comes from). Declaring a child (`mod x;`) is not an edge;
//! using its items is.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a file without comments (line comments, doc comments, block comments) and
/// without string literals' contents.
fn code_only(text: &str) -> String {
    strip(text, false)
}

/// `text` without comments, and without string literals' contents unless `keep_strings`
/// (then without the braces in them).
fn strip(text: &str, keep_strings: bool) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            while i < b.len() && !b[i..].starts_with(b"*/") {
                i += 1;
            }
            i += 2;
        } else if b[i] == b'"' {
            let start = i;
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            if keep_strings {
                // Braces inside a string would mislead the brace matching of inline
                // modules; a `#[path]` never holds one.
                out.extend(text[start..i.min(b.len())].chars().map(|c| {
                    if c == '{' || c == '}' {
                        ' '
                    } else {
                        c
                    }
                }));
            } else {
                out.push_str("\"\"");
            }
        } else {
            out.push(b[i] as char);
            i += 1;
        }
    }
    out
}

/// Every path that starts with `head::` in `code`, as its segments (a `{` group is
/// expanded one level: `crate::a::{b, c::d}` gives `a::b` and `a::c::d`).
fn paths_after(code: &str, head: &str) -> Vec<Vec<String>> {
    located_paths(code, head)
        .into_iter()
        .map(|(_, p)| p)
        .collect()
}

/// [`paths_after`] with the offset of each path's head in `code`. A head that continues a
/// path (`a::head::`) or a name (`xhead::`) does not start one.
fn located_paths(code: &str, head: &str) -> Vec<(usize, Vec<String>)> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let pat = format!("{head}::");
    let mut from = 0;
    while let Some(k) = code[from..].find(&pat) {
        let start = from + k;
        from = start + pat.len();
        if start > 0 && ident(code[..start].chars().last().unwrap())
            || code[..start].trim_end().ends_with("::")
        {
            continue;
        }
        let rest = &code[from..];
        let mut segs = Vec::new();
        let mut pos = 0;
        loop {
            let len = rest[pos..].chars().take_while(|&c| ident(c)).count();
            if len == 0 {
                break;
            }
            segs.push(rest[pos..pos + len].to_string());
            pos += len;
            if rest[pos..].starts_with("::") {
                pos += 2;
            } else {
                break;
            }
        }
        if rest[pos..].starts_with('{') {
            let end = rest[pos..].find('}').map_or(rest.len(), |e| pos + e);
            for item in rest[pos + 1..end].split(',') {
                let mut s = segs.clone();
                s.extend(
                    item.trim()
                        .split("::")
                        .map(|x| x.trim().to_string())
                        .filter(|x| !x.is_empty() && x.chars().all(ident)),
                );
                out.push((start, s));
            }
        } else {
            out.push((start, segs));
        }
    }
    out
}

/// A crate's source files: path relative to `src` → text.
type Sources = BTreeMap<PathBuf, String>;

fn read_sources(src: &Path) -> Sources {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files
        .into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(&f).unwrap();
            (f.strip_prefix(src).unwrap().to_path_buf(), text)
        })
        .collect()
}

/// One module of the tree: its code (without comments and strings) and the children it
/// declares.
struct Module {
    code: String,
    children: BTreeSet<String>,
}

/// Every `mod NAME` item of `code`: where `mod` starts, NAME, and where the first
/// character after NAME (`;` for a declaration, `{` for an inline module) is.
fn mod_items(code: &str) -> Vec<(usize, String, usize)> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("mod ") {
        let at = from + k;
        from = at + 4;
        if at > 0 && ident(code[..at].chars().last().unwrap()) {
            continue;
        }
        let rest = code[from..].trim_start();
        let name: String = rest.chars().take_while(|&c| ident(c)).collect();
        let after = rest[name.len()..].trim_start();
        if !name.is_empty() {
            out.push((at, name, code.len() - after.len()));
        }
    }
    out
}

/// The `mod x;` declarations of a file outside inline modules, with the file a
/// `#[path = "…"]` on each names.
fn declarations(text: &str) -> Vec<(String, Option<String>)> {
    let code = strip(text, true);
    let inline = inline_modules(&code);
    let mut out = Vec::new();
    for (at, name, next) in mod_items(&code) {
        // Inside an inline module, a declaration names a file elsewhere: none here do.
        if !code[next..].starts_with(';') || inline.iter().any(|(_, r)| r.contains(&at)) {
            continue;
        }
        // The attributes since the previous item.
        let item_start = code[..at].rfind([';', '}', '{']).map_or(0, |e| e + 1);
        let attrs = &code[item_start..at];
        let path = attrs.find("#[path").map(|p| {
            let q = attrs[p..].find('"').unwrap() + p + 1;
            let e = attrs[q..].find('"').unwrap() + q;
            attrs[q..e].to_string()
        });
        out.push((name, path));
    }
    out
}

/// The inline modules of a file's code (`mod tests { … }`): name and byte range.
fn inline_modules(code: &str) -> Vec<(String, std::ops::Range<usize>)> {
    let mut out = Vec::new();
    for (_, name, open) in mod_items(code) {
        if !code[open..].starts_with('{') {
            continue;
        }
        let mut depth = 0;
        let mut end = code.len();
        for (i, c) in code[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + i + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        out.push((name, open..end));
    }
    out
}

/// The modules of the crate in `sources`, found from `lib.rs` by their declarations.
fn modules(sources: &Sources) -> BTreeMap<String, Module> {
    let mut out = BTreeMap::new();
    let mut todo = vec![(String::new(), PathBuf::from("lib.rs"))];
    while let Some((name, file)) = todo.pop() {
        let text = sources
            .get(&file)
            .unwrap_or_else(|| panic!("module `{name}`: no file {}", file.display()));
        let dir = file.parent().unwrap_or(Path::new("")).to_path_buf();
        let owns_dir = matches!(
            file.file_name().and_then(|f| f.to_str()),
            Some("lib.rs" | "mod.rs" | "main.rs")
        );
        let mut children = BTreeSet::new();
        for (child, path) in declarations(text) {
            let child_file = match path {
                Some(p) => dir.join(p),
                None => {
                    let base = if owns_dir {
                        dir.clone()
                    } else {
                        dir.join(file.file_stem().unwrap())
                    };
                    let flat = base.join(format!("{child}.rs"));
                    if sources.contains_key(&flat) {
                        flat
                    } else {
                        base.join(&child).join("mod.rs")
                    }
                }
            };
            let child_name = if name.is_empty() {
                child.clone()
            } else {
                format!("{name}::{child}")
            };
            todo.push((child_name, child_file));
            children.insert(child);
        }
        out.insert(
            name,
            Module {
                code: code_only(text),
                children,
            },
        );
    }
    out
}

/// The module graph of the library crate whose sources are in `src`.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    graph_of(&read_sources(src))
}

/// The module graph of the crate in `sources`.
fn graph_of(sources: &Sources) -> BTreeMap<String, BTreeSet<String>> {
    let code = modules(sources);
    let modules: BTreeSet<String> = code.keys().cloned().collect();
    // The crate root's re-exports: name -> the module it comes from.
    let mut root_names = BTreeMap::new();
    for p in paths_after(
        &code[""].code.replace("pub use ", "pub use crate::"),
        "crate",
    ) {
        if let Some(name) = p.last() {
            root_names.insert(name.clone(), p[..p.len() - 1].join("::"));
        }
    }
    // The longest module prefix of an absolute path.
    let resolve = |segs: &[String]| -> Option<String> {
        (1..=segs.len())
            .rev()
            .map(|n| segs[..n].join("::"))
            .find(|m| modules.contains(m))
            .or_else(|| segs.first().and_then(|s| root_names.get(s).cloned()))
    };
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, module) in &code {
        let deps = graph.entry(m.clone()).or_default();
        if m.is_empty() {
            continue; // the root only declares and re-exports
        }
        let text = &module.code;
        let own: Vec<String> = m.split("::").map(String::from).collect();
        let inline = inline_modules(text);
        // The module a path at `at` is written in: the file's, and the inline modules
        // around it.
        let scope = |at: usize| -> Vec<String> {
            let mut v = own.clone();
            v.extend(
                inline
                    .iter()
                    .filter(|(_, r)| r.contains(&at))
                    .map(|(n, _)| n.clone()),
            );
            v
        };
        let mut targets = Vec::new();
        for (_, p) in located_paths(text, "crate") {
            targets.extend(resolve(&p));
        }
        for (at, p) in located_paths(text, "self") {
            let mut abs = scope(at);
            abs.extend(p);
            targets.extend(resolve(&abs));
        }
        for (at, p) in located_paths(text, "super") {
            let mut abs = scope(at);
            abs.pop();
            // `super::super::x`: one level up for each.
            let ups = p.iter().take_while(|s| *s == "super").count();
            for _ in 0..ups {
                abs.pop();
            }
            let parent = abs.join("::");
            abs.extend(p.into_iter().skip(ups));
            targets.extend(resolve(&abs).or(Some(parent)));
        }
        for child in &module.children {
            for (_, p) in located_paths(text, child) {
                let mut abs = own.clone();
                abs.push(child.clone());
                abs.extend(p);
                targets.extend(resolve(&abs));
            }
        }
        for t in targets {
            if t != *m && !t.is_empty() {
                deps.insert(t);
            }
        }
    }
    graph
}

/// A cycle in `graph`, as the modules along it, if there is one.
fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for d in graph.get(n).into_iter().flatten() {
            match state.get(d.as_str()).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|s| s == d).unwrap();
                    let mut c = stack[at..].to_vec();
                    c.push(d.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(d, graph, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        if state.get(n.as_str()).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(n, graph, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

/// The graph with each top-level module and everything under it as one node (a folder
/// such as `shapes/` is one part of the architecture).
fn top_level(graph: &BTreeMap<String, BTreeSet<String>>) -> BTreeMap<String, BTreeSet<String>> {
    let top = |m: &str| m.split("::").next().unwrap_or("").to_string();
    let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, deps) in graph {
        let node = out.entry(top(m)).or_default();
        node.extend(deps.iter().map(|d| top(d)).filter(|d| *d != top(m)));
    }
    out
}

fn assert_acyclic(krate: &str) {
    let graph = module_graph(&repo().join(krate).join("src"));
    assert!(
        graph.len() > 5,
        "{krate}: found only {} modules",
        graph.len()
    );
    for (level, g) in [
        ("module", graph.clone()),
        ("top-level module", top_level(&graph)),
    ] {
        if let Some(c) = find_cycle(&g) {
            panic!(
                "{krate}/src has a {level} import cycle: {} (each uses the next; \
                 ARCHITECTURE.md says where each part belongs)",
                c.join(" → ")
            );
        }
    }
}

#[test]
fn renderer_modules_import_one_way() {
    assert_acyclic("renderer");
}

#[test]
fn conformance_modules_import_one_way() {
    assert_acyclic("conformance");
}

#[test]
fn the_checker_sees_a_cycle() {
    let mut g = module_graph(&repo().join("renderer/src"));
    assert!(
        g["aggregate"].contains("shapes") && g["shading"].contains("scene"),
        "the graph misses known edges: {g:?}"
    );
    assert!(find_cycle(&g).is_none());
    // One shape importing the aggregate back (as they all did before the hit record had
    // its own module) is a cycle between the parts.
    assert!(find_cycle(&top_level(&g)).is_none());
    g.get_mut("shapes::sphere")
        .unwrap()
        .insert("aggregate".into());
    let c = find_cycle(&top_level(&g)).expect("a cycle between parts");
    assert!(c.contains(&"shapes".to_string()) && c.contains(&"aggregate".to_string()));
    g.get_mut("shapes").unwrap().insert("aggregate".into());
    let c = find_cycle(&g).expect("a cycle");
    assert!(c.contains(&"shapes".to_string()) && c.contains(&"aggregate".to_string()));
    // A child using its parent and the parent using the child back is one too.
    let code = "use super::Scene; fn f() { crate::scene::build::x(); }";
    assert_eq!(paths_after(code, "super"), vec![vec!["Scene".to_string()]]);
    assert_eq!(
        paths_after("use crate::a::{b, c::d};", "crate"),
        vec![
            vec!["a".to_string(), "b".to_string()],
            vec!["a".to_string(), "c".to_string(), "d".to_string()]
        ]
    );
}

#[test]
fn the_renderer_never_depends_on_conformance() {
    let manifest = std::fs::read_to_string(repo().join("renderer/Cargo.toml")).unwrap();
    assert!(
        !manifest.contains("conformance"),
        "renderer/Cargo.toml names the conformance crate: the dependency must point one way"
    );
    let mut files = Vec::new();
    rust_files(&repo().join("renderer/src"), &mut files);
    for f in files {
        let code = code_only(&std::fs::read_to_string(&f).unwrap());
        assert!(
            !code.contains("conformance::"),
            "{} uses the conformance crate",
            f.display()
        );
    }
}

/// Sources from (path under `src`, text) pairs.
fn sources(files: &[(&str, &str)]) -> Sources {
    files
        .iter()
        .map(|(p, t)| (PathBuf::from(p), t.to_string()))
        .collect()
}

fn set<const N: usize>(names: [&str; N]) -> BTreeSet<String> {
    names.into_iter().map(String::from).collect()
}

#[test]
fn the_checker_names_path_modules_and_sees_bare_child_paths() {
    // The renderer's layout before issue 38: `physical` declared `light_paths` by
    // `#[path]` and used it by a bare path, and `light_paths` used its parent (`super::*`)
    // and the render loop, which used `physical`.
    let old = [
        ("lib.rs", "pub mod physical;\npub mod render;\n"),
        (
            "physical.rs",
            "//! The model.\n#[path = \"light_paths.rs\"]\nmod light_paths;\npub(crate) use light_paths::fold;\npub struct PhysicalIntegrator;\n",
        ),
        (
            "light_paths.rs",
            "use super::*;\nuse crate::render::{add_moment_products, MOMENT_PAIRS};\npub fn fold() {}\n",
        ),
        (
            "render.rs",
            "use crate::physical::PhysicalIntegrator;\npub fn add_moment_products() {}\n#[cfg(test)]\nmod tests {\n    use super::*;\n}\n",
        ),
    ];
    let g = graph_of(&sources(&old));
    assert!(
        !g.contains_key("light_paths"),
        "a #[path] module named by its file: {g:?}"
    );
    assert_eq!(g["physical::light_paths"], set(["physical", "render"]));
    assert_eq!(
        g["physical"],
        set(["physical::light_paths"]),
        "bare child path"
    );
    // `super` inside render's inline `mod tests` is render itself: no edge.
    assert_eq!(g["render"], set(["physical"]));
    let c = find_cycle(&g).expect("physical and its child use each other");
    assert!(c.contains(&"physical::light_paths".to_string()), "{c:?}");
    let c = find_cycle(&top_level(&g)).expect("physical and render use each other");
    assert!(
        c.contains(&"physical".to_string()) && c.contains(&"render".to_string()),
        "{c:?}"
    );
    // The layout of issue 38: the moment products in a module both import, and the child
    // using a sibling, not its parent.
    let new = [
        (
            "lib.rs",
            "pub mod image;\npub mod physical;\npub mod render;\n",
        ),
        ("image.rs", "pub fn add_moment_products() {}\n"),
        (
            "physical/mod.rs",
            "mod bsdf;\nmod light_paths;\npub(crate) use light_paths::fold;\n",
        ),
        (
            "physical/bsdf.rs",
            "pub(super) struct Surface;\n#[cfg(test)]\nmod tests {\n    use super::*;\n}\n",
        ),
        (
            "physical/light_paths.rs",
            "use super::bsdf::Surface;\nuse crate::image::add_moment_products;\npub fn fold() {}\n",
        ),
        (
            "render.rs",
            "use crate::image::add_moment_products;\nuse crate::physical::fold;\n",
        ),
    ];
    let g = graph_of(&sources(&new));
    assert_eq!(g["physical::light_paths"], set(["image", "physical::bsdf"]));
    // `super` in an inline `mod tests` is the file's own module, not its parent.
    assert_eq!(g["physical::bsdf"], set([]));
    assert!(find_cycle(&g).is_none(), "{g:?}");
    assert!(find_cycle(&top_level(&g)).is_none(), "{g:?}");
    // `super::super`, `self::` and a `#[path]` beside a folder's `mod.rs`.
    let g = graph_of(&sources(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        (
            "a/mod.rs",
            "#[path = \"inner.rs\"]\nmod c;\nfn f() { self::c::g(); }\n",
        ),
        ("a/inner.rs", "fn g() { super::super::b::h(); }\n"),
        ("b.rs", "fn h() {}\n"),
    ]));
    assert_eq!(g["a"], set(["a::c"]));
    assert_eq!(g["a::c"], set(["b"]));
}

#[test]
fn a_cycle_planted_in_the_renderer_is_caught() {
    let clean = read_sources(&repo().join("renderer/src"));
    assert!(find_cycle(&graph_of(&clean)).is_none());
    for (file, planted, between) in [
        // The light paths using the render loop again (for the moment products, as they
        // did): render uses physical, which uses its light paths.
        (
            "physical/light_paths.rs",
            "\nuse crate::render::Options;\n",
            ["physical::light_paths", "render"],
        ),
        // A child using its parent's re-export: the parent uses the child's sibling,
        // which uses the child.
        (
            "physical/bsdf.rs",
            "\nfn planted(_: super::PhysicalIntegrator) {}\n",
            ["physical::bsdf", "physical"],
        ),
    ] {
        let mut s = clean.clone();
        s.get_mut(Path::new(file))
            .unwrap_or_else(|| panic!("no renderer/src/{file}"))
            .push_str(planted);
        let g = graph_of(&s);
        let c = find_cycle(&g).unwrap_or_else(|| panic!("{file} + {planted:?}: no cycle found"));
        for m in between {
            assert!(c.contains(&m.to_string()), "{file} + {planted:?}: {c:?}");
        }
    }
}
