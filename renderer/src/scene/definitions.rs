//! The definitions a scene names: refused when one contains itself or when they nest
//! deeper than [`MAX_NESTING`].

use super::error::{SceneError, Source};
use super::format::NodeDesc;
use std::collections::{BTreeMap, HashMap};
use toml::Spanned;

/// How deep definitions may place one another (`defs.a` placing `defs.b` placing …), and
/// groups may nest: deeper inputs are refused with a located error (renderer/docs/
/// robustness.md). It bounds the recursion of building and of tracing.
pub const MAX_NESTING: usize = 64;

/// The definitions a node places (its `of`, and its children's), in file order.
fn placed<'n>(node: &'n NodeDesc, out: &mut Vec<&'n Spanned<String>>) {
    if let Some(of) = &node.of {
        out.push(of);
    }
    for c in node.children.iter().flatten() {
        placed(c.get_ref(), out);
    }
}

/// Refuses a definition that places itself, directly or through others (placed anywhere
/// or not), naming the chain, and chains of definitions deeper than [`MAX_NESTING`].
pub(super) fn check_definitions(
    defs: &BTreeMap<String, Spanned<NodeDesc>>,
    src: &Source,
) -> Result<(), SceneError> {
    // Depth of each definition's chain, once known.
    let mut depth: HashMap<&str, usize> = HashMap::new();
    fn visit<'d>(
        name: &'d str,
        defs: &'d BTreeMap<String, Spanned<NodeDesc>>,
        src: &Source,
        stack: &mut Vec<(&'d str, Option<&'d Spanned<String>>)>,
        depth: &mut HashMap<&'d str, usize>,
    ) -> Result<usize, SceneError> {
        if let Some(&d) = depth.get(name) {
            return Ok(d);
        }
        let Some(node) = defs.get(name) else {
            return Ok(0); // A missing definition is reported where it is placed.
        };
        let mut refs = Vec::new();
        placed(node.get_ref(), &mut refs);
        let mut deepest = 0;
        for of in refs {
            let next = of.get_ref().as_str();
            let chain = |stack: &[(&str, Option<&Spanned<String>>)], last: &str| {
                stack
                    .iter()
                    .map(|(n, _)| format!("defs.{n}"))
                    .chain(std::iter::once(format!("defs.{last}")))
                    .collect::<Vec<_>>()
                    .join(" → ")
            };
            if stack.iter().any(|(n, _)| *n == next) || next == name {
                let mut full = stack.clone();
                full.push((name, None));
                let from = full.iter().position(|(n, _)| *n == next).unwrap_or(0);
                return Err(src.error(
                    of.span().start,
                    format!("defs.{name}.of"),
                    format!(
                        "definition '{next}' contains itself: {}",
                        chain(&full[from..], next)
                    ),
                ));
            }
            if stack.len() + 1 >= MAX_NESTING {
                let mut full = stack.clone();
                full.push((name, None));
                let shown = if full.len() > 6 {
                    format!(
                        "{} → … → {}",
                        chain(&full[..2], full[2].0),
                        chain(&full[full.len() - 2..], next)
                    )
                } else {
                    chain(&full, next)
                };
                return Err(src.error(
                    of.span().start,
                    format!("defs.{name}.of"),
                    format!(
                        "definitions nest deeper than {MAX_NESTING} levels ({shown}); \
flatten the chain"
                    ),
                ));
            }
            stack.push((name, Some(of)));
            let d = visit(next, defs, src, stack, depth)?;
            stack.pop();
            if stack.len() + d + 1 >= MAX_NESTING {
                return Err(src.error(
                    of.span().start,
                    format!("defs.{name}.of"),
                    format!(
                        "definitions nest deeper than {MAX_NESTING} levels (defs.{name} → defs.{next} → … \
{} more); flatten the chain",
                        d
                    ),
                ));
            }
            deepest = deepest.max(d + 1);
        }
        depth.insert(name, deepest);
        Ok(deepest)
    }
    for name in defs.keys() {
        visit(name, defs, src, &mut Vec::new(), &mut depth)?;
    }
    Ok(())
}
