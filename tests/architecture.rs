//! The architecture invariants that code can check: no module of the renderer or the
//! conformance crate imports a module that imports it back (directly or through others),
//! and the renderer never depends on the conformance crate.
//!
//! Edges are read from the source: every `crate::a::b` and `super::x` path outside
//! comments, resolved to the longest module prefix (a re-export of the crate root is
//! followed to the module it comes from). Declaring a child (`mod x;`) is not an edge;
//! using its items is.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Module path of a source file relative to `src`: `lib.rs` is "", `a/mod.rs` is "a",
/// `a/b.rs` is "a::b". Files under `bin/` and `main.rs` are separate crates and skipped.
fn module_of(rel: &Path) -> Option<String> {
    let parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if parts[0] == "bin" || rel == Path::new("main.rs") {
        return None;
    }
    let mut v: Vec<String> = parts.clone();
    let last = v.pop()?;
    let stem = last.strip_suffix(".rs")?;
    if stem != "mod" && stem != "lib" {
        v.push(stem.to_string());
    }
    Some(v.join("::"))
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
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
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
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let pat = format!("{head}::");
    let mut from = 0;
    while let Some(k) = code[from..].find(&pat) {
        let start = from + k;
        from = start + pat.len();
        if start > 0 && ident(code[..start].chars().last().unwrap()) {
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
                out.push(s);
            }
        } else {
            out.push(segs);
        }
    }
    out
}

/// The module graph of the library crate whose sources are in `src`.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut code = BTreeMap::new();
    for f in &files {
        if let Some(m) = module_of(f.strip_prefix(src).unwrap()) {
            code.insert(m, code_only(&std::fs::read_to_string(f).unwrap()));
        }
    }
    let modules: BTreeSet<String> = code.keys().cloned().collect();
    // The crate root's re-exports: name -> the module it comes from.
    let mut root_names = BTreeMap::new();
    for p in paths_after(&code[""].replace("pub use ", "pub use crate::"), "crate") {
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
    for (m, text) in &code {
        let deps = graph.entry(m.clone()).or_default();
        if m.is_empty() {
            continue; // the root only declares and re-exports
        }
        let parent: Vec<String> = {
            let mut v: Vec<String> = m.split("::").map(String::from).collect();
            v.pop();
            v
        };
        let mut targets = Vec::new();
        for p in paths_after(text, "crate") {
            targets.extend(resolve(&p));
        }
        for p in paths_after(text, "super") {
            let mut abs = parent.clone();
            abs.extend(p);
            targets.extend(resolve(&abs).or(Some(parent.join("::"))));
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
