//! Numbers that are finite as written but not in the renderer's precision, refused where
//! they are written.

use super::error::{SceneError, Source};
use crate::real::Real;

/// Refuses numbers that are finite as written (in f64) but not in the renderer's precision
/// (|x| above `Real::MAX`, 3.4e38 in the f32 build): converted, they would become
/// infinite and the image would come out black or with zeroed pixels, silently. Integers
/// too large for an f64 are left to the typed fields, which refuse them.
pub(super) fn check_precision(
    table: &toml::Spanned<toml::de::DeTable<'_>>,
    src: &Source,
) -> Result<(), SceneError> {
    use toml::de::DeValue;
    /// A number's value, read only when it could be out of range: its digits (before an
    /// exponent) or its exponent are long. Most numbers of a scene are short and skipped.
    fn number(v: &DeValue) -> Option<f64> {
        let text = match v {
            DeValue::Float(f) => f.as_str(),
            DeValue::Integer(i) if i.radix() == 10 => i.as_str(),
            _ => return None,
        };
        // |x| ≤ 3.4e38 whenever the mantissa has at most 38 digits and there is no
        // exponent: skip those without parsing.
        if text.len() < 38 && !text.contains(['e', 'E']) {
            return None;
        }
        text.replace('_', "").parse().ok()
    }
    enum Seg<'k> {
        Key(&'k str),
        Index(usize),
    }
    fn path_of(segs: &[Seg]) -> String {
        let mut p = String::new();
        for s in segs {
            match s {
                Seg::Key(k) if p.is_empty() => p.push_str(k),
                Seg::Key(k) => {
                    p.push('.');
                    p.push_str(k)
                }
                Seg::Index(i) => p.push_str(&format!("[{i}]")),
            }
        }
        p
    }
    fn walk<'k>(
        v: &'k toml::Spanned<DeValue<'k>>,
        segs: &mut Vec<Seg<'k>>,
        src: &Source,
    ) -> Result<(), SceneError> {
        match v.get_ref() {
            DeValue::Table(t) => {
                for (k, val) in t.iter() {
                    segs.push(Seg::Key(k.get_ref()));
                    walk(val, segs, src)?;
                    segs.pop();
                }
            }
            DeValue::Array(a) => {
                for (i, val) in a.iter().enumerate() {
                    segs.push(Seg::Index(i));
                    walk(val, segs, src)?;
                    segs.pop();
                }
            }
            other => {
                if let Some(x) = number(other) {
                    if x.is_finite() && x.abs() > Real::MAX as f64 {
                        return Err(src.error(
                            v.span().start,
                            path_of(segs),
                            format!(
                                "{x:e} is beyond the largest number of the renderer's precision \
({}, largest {:e}); scale the scene down, or use the f64 build",
                                crate::real::PRECISION,
                                Real::MAX
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
    let mut segs = Vec::new();
    for (k, val) in table.get_ref().iter() {
        segs.push(Seg::Key(k.get_ref()));
        walk(val, &mut segs, src)?;
        segs.pop();
    }
    Ok(())
}
