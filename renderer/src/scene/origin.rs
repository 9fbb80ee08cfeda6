//! Render space: where its origin goes (renderer/docs/precision.md, "Render-space origin").

use crate::aggregate::Aggregate;
use glam::DVec3;

/// Where render space's origin goes, in world coordinates: the eye, when the eye is
/// farther from the world origin than twice its distance to every object (then every
/// object is nearer the eye than the world origin is, so moving the origin to the eye
/// makes every coordinate smaller, and so more precise, in the render precision);
/// otherwise the world origin stays (0). A bounded object counts by its box; an unbounded
/// one (a plane) by the point its transform places at its object-space origin.
/// renderer/docs/precision.md measures what it buys.
pub(super) fn render_origin(root: &Aggregate, eye: DVec3) -> DVec3 {
    let dv = crate::real::dvec3;
    let mut reach: f64 = root.bounded_bounds().map_or(0.0, |b| {
        // The farthest corner of the bounded objects' box from the eye.
        (eye - dv(b.min))
            .abs()
            .max((eye - dv(b.max)).abs())
            .length()
    });
    for inst in root.unbounded_instances() {
        let anchor = inst.xf.map_or(DVec3::ZERO, |x| dv(x.translation()));
        reach = reach.max((eye - anchor).length());
    }
    if eye.length() > 2.0 * reach {
        eye
    } else {
        DVec3::ZERO
    }
}
