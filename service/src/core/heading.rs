//! Heading sources behind one interface: map-free dominant directions (a building grid), a
//! corridor map, or nothing; the ψ/ψ+π association and the straight-walk test.
//!
//! A source answers one question: given the foot's position and its (estimated) walking heading
//! in the map frame, which direction should it be walking in, if any? External heading
//! observations (magnetometer, GNSS, a map matcher) bypass the source: the estimator queues them.

use super::rotation::wrap_pi;
use serde::Deserialize;
use std::f64::consts::PI;

/// One straight corridor: a segment with a width, in the map frame.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Corridor {
    /// Name, for logs.
    #[serde(default)]
    pub name: String,
    /// One end, metres.
    pub from_m: [f64; 2],
    /// The other end, metres.
    pub to_m: [f64; 2],
    /// Full width, metres.
    pub width_m: f64,
}

impl Corridor {
    /// Direction of the corridor axis (from → to), rad.
    pub fn axis_rad(&self) -> f64 {
        (self.to_m[1] - self.from_m[1]).atan2(self.to_m[0] - self.from_m[0])
    }

    /// Whether `xy` lies inside the corridor (within half the width of the segment).
    pub fn contains(&self, xy: [f64; 2]) -> bool {
        let (ax, ay) = (self.from_m[0], self.from_m[1]);
        let (dx, dy) = (self.to_m[0] - ax, self.to_m[1] - ay);
        let len2 = dx * dx + dy * dy;
        if len2 <= 0.0 {
            return false;
        }
        let s = ((xy[0] - ax) * dx + (xy[1] - ay) * dy) / len2;
        if !(0.0..=1.0).contains(&s) {
            return false;
        }
        let (px, py) = (ax + s * dx - xy[0], ay + s * dy - xy[1]);
        (px * px + py * py).sqrt() <= 0.5 * self.width_m
    }
}

/// A corridor map file: `[[corridor]]` tables.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CorridorMap {
    /// The corridors.
    #[serde(default, rename = "corridor")]
    pub corridors: Vec<Corridor>,
}

/// A corridor whose geometry cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("corridor {index} ({name:?}): {problem}")]
pub struct GeometryError {
    /// 0-based index in the map.
    pub index: usize,
    /// Its name.
    pub name: String,
    /// What is wrong.
    pub problem: String,
}

/// Narrowest and shortest corridor a map may hold, m: a foot's width. One narrower or shorter
/// contains no footprint, and one at 1e300 m overflowed the test of a footprint inside it: either
/// took every heading observation along it away, silently (a review).
pub const MIN_CORRIDOR_M: f64 = 0.1;

/// Largest corridor coordinate and width, m: the survey's bound
/// ([`corridor_shared::truth_csv::MAX_COORDINATE_M`], 1000 km from the origin).
pub const MAX_CORRIDOR_M: f64 = corridor_shared::truth_csv::MAX_COORDINATE_M;

impl CorridorMap {
    /// Checks every corridor: a width in [[`MIN_CORRIDOR_M`], [`MAX_CORRIDOR_M`]], ends within
    /// [`MAX_CORRIDOR_M`] of the origin and at least [`MIN_CORRIDOR_M`] apart.
    pub fn check(&self) -> Result<(), GeometryError> {
        for (index, c) in self.corridors.iter().enumerate() {
            let bad = |problem: String| GeometryError {
                index,
                name: c.name.clone(),
                problem,
            };
            if !(c.width_m.is_finite() && c.width_m > 0.0) {
                return Err(bad(format!("width_m = {} must be > 0", c.width_m)));
            }
            if !(MIN_CORRIDOR_M..=MAX_CORRIDOR_M).contains(&c.width_m) {
                return Err(bad(format!(
                    "width_m = {:?} must be in [{MIN_CORRIDOR_M}, {MAX_CORRIDOR_M:e}] m",
                    c.width_m
                )));
            }
            let ends = format!("from_m = {:?}, to_m = {:?}", c.from_m, c.to_m);
            if c.from_m
                .iter()
                .chain(&c.to_m)
                .any(|v| !(-MAX_CORRIDOR_M..=MAX_CORRIDOR_M).contains(v))
            {
                return Err(bad(format!(
                    "{ends}: each coordinate must be finite and within ±{MAX_CORRIDOR_M:e} m"
                )));
            }
            let length_m = (c.to_m[0] - c.from_m[0]).hypot(c.to_m[1] - c.from_m[1]);
            if length_m < MIN_CORRIDOR_M {
                return Err(bad(format!(
                    "{ends}: the ends are {length_m:?} m apart, a corridor must be at least \
                     {MIN_CORRIDOR_M} m long"
                )));
            }
        }
        Ok(())
    }
}

/// Where heading observations come from.
#[derive(Debug, Clone)]
pub enum HeadingAid {
    /// None.
    None,
    /// Dominant directions `grid_rad + k·step_rad`.
    Grid {
        /// Orientation.
        grid_rad: f64,
        /// Spacing.
        step_rad: f64,
    },
    /// Corridor map.
    Map(CorridorMap),
}

/// Why a heading observation was not used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rejection {
    /// The foot turned too much over the last strides.
    NotStraight,
    /// No direction within the gate.
    OutsideGate,
    /// Not inside any corridor of the map.
    OutsideMap,
    /// The association weight was too low: the walker is most likely not walking along the
    /// nearest direction (a weave, a side-step, a turn).
    Unlikely,
    /// The foot axis points along a direction the stride that brought it there does not
    /// follow (`heading.foot_axis_stride_max_deg`): a weave.
    OffStride,
    /// No heading source.
    NoSource,
}

impl Rejection {
    /// Stable name for counters and CSV.
    pub fn name(self) -> &'static str {
        match self {
            Rejection::NotStraight => "not_straight",
            Rejection::OutsideGate => "outside_gate",
            Rejection::OutsideMap => "outside_map",
            Rejection::Unlikely => "unlikely",
            Rejection::OffStride => "off_stride",
            Rejection::NoSource => "no_source",
        }
    }
}

impl HeadingAid {
    /// `"none"`, `"grid"` or `"map"` (as `heading.source` names them).
    pub fn name(&self) -> &'static str {
        match self {
            HeadingAid::None => "none",
            HeadingAid::Grid { .. } => "grid",
            HeadingAid::Map(_) => "map",
        }
    }

    /// The associated direction (rad, map frame) for a foot at `xy` walking at `heading_rad`,
    /// the nearest of the candidate directions within `gate_rad`.
    pub fn associate(
        &self,
        xy: [f64; 2],
        heading_rad: f64,
        gate_rad: f64,
    ) -> Result<f64, Rejection> {
        self.associate_among(xy, heading_rad, gate_rad)
            .map(|(dir, _)| dir)
    }

    /// [`HeadingAid::associate`], and the candidate directions there, relative to the one
    /// associated (for its weight: `association_weight`).
    pub fn associate_among(
        &self,
        xy: [f64; 2],
        heading_rad: f64,
        gate_rad: f64,
    ) -> Result<(f64, Candidates), Rejection> {
        match self {
            HeadingAid::None => Err(Rejection::NoSource),
            HeadingAid::Grid { grid_rad, step_rad } => {
                let k = ((heading_rad - grid_rad) / step_rad).round();
                let dir = wrap_pi(grid_rad + k * step_rad);
                if wrap_pi(heading_rad - dir).abs() <= gate_rad {
                    Ok((
                        dir,
                        Candidates::Spaced {
                            spacing_rad: *step_rad,
                        },
                    ))
                } else {
                    Err(Rejection::OutsideGate)
                }
            }
            HeadingAid::Map(map) => {
                // The nearest direction of every corridor containing `xy` ...
                let inside = || map.corridors.iter().filter(|c| c.contains(xy));
                let directions =
                    || inside().flat_map(|c| [c.axis_rad(), c.axis_rad() + PI].map(wrap_pi));
                let off = |d: f64| wrap_pi(heading_rad - d).abs();
                let dir = directions()
                    .min_by(|&a, &b| off(a).total_cmp(&off(b)))
                    .ok_or(Rejection::OutsideMap)?;
                if off(dir) > gate_rad {
                    return Err(Rejection::OutsideGate);
                }
                // ... and the directions there for its weight, the associated one first, each
                // once (overlapping segments of one corridor drawn a few degrees apart are one
                // direction).
                let mut offsets_rad = [0.0; MAX_LISTED_DIRECTIONS];
                let mut n = 1;
                for d in directions() {
                    let o = wrap_pi(d - dir);
                    let known = offsets_rad[..n]
                        .iter()
                        .any(|&k| wrap_pi(o - k).abs() < SAME_DIRECTION_RAD);
                    if !known && n < MAX_LISTED_DIRECTIONS {
                        offsets_rad[n] = o;
                        n += 1;
                    }
                }
                Ok((
                    dir,
                    if n == 2 {
                        // One corridor (or parallel ones): its ψ and ψ + π.
                        Candidates::Spaced { spacing_rad: PI }
                    } else {
                        Candidates::Listed {
                            offsets_rad,
                            n: n as u8,
                        }
                    },
                ))
            }
        }
    }
}

/// At most this many distinct directions weigh an association where corridors of a map cross
/// (eight corridor axes through one place); a ninth axis there is left out of the weight (the
/// association itself takes the nearest of all).
pub const MAX_LISTED_DIRECTIONS: usize = 16;

/// Corridor directions closer than this are one direction for the association weight: a
/// corridor drawn as overlapping segments a few degrees apart is one corridor (with a 1e-9 rad
/// tolerance, two segments 0.3° apart halved the weight of a stride along them, a review), and
/// the corridors of a junction meet at tens of degrees.
const SAME_DIRECTION_RAD: f64 = 5.0 * PI / 180.0;

/// The directions a walker at one place may walk along, relative to the one an observation was
/// associated with: evenly spaced around the circle (a grid's step, or π for one corridor's ψ
/// and ψ + π), or listed where corridors of a map cross (each corridor's two directions, once;
/// `offsets_rad[0]` is the associated one's, 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Candidates {
    /// Around the circle at this spacing.
    Spaced {
        /// Spacing, rad.
        spacing_rad: f64,
    },
    /// The first `n` of `offsets_rad`.
    Listed {
        /// Each direction minus the associated one, wrapped to ±π.
        offsets_rad: [f64; MAX_LISTED_DIRECTIONS],
        /// How many there are.
        n: u8,
    },
}

/// The straight-walk test: the foot heading at each of the previous `n` stances lies within
/// `max_change_rad` of this stance's (so those earlier headings may spread by up to twice that
/// among themselves). Fixed capacity, no allocation after `new`.
#[derive(Debug, Clone)]
pub struct StraightWalk {
    history: Vec<f64>,
    len: usize,
    next: usize,
    max_change_rad: f64,
}

impl StraightWalk {
    /// Becomes a copy of `src` in its own history: no allocation when it is as long. Every
    /// other field is `Copy` (see `StanceDetector::copy_from`).
    pub fn copy_from(&mut self, src: &Self) {
        let mut history = std::mem::take(&mut self.history);
        history.clone_from(&src.history);
        *self = Self { history, ..*src };
    }

    /// Looks back over `n` stances.
    pub fn new(n: usize, max_change_rad: f64) -> Self {
        Self {
            history: vec![0.0; n.max(1)],
            len: 0,
            next: 0,
            max_change_rad,
        }
    }

    /// Records this stance's heading and says whether the walk was straight.
    pub fn push(&mut self, heading_rad: f64) -> bool {
        let n = self.history.len();
        let straight = self.len == n
            && self
                .history
                .iter()
                .all(|h| wrap_pi(heading_rad - h).abs() <= self.max_change_rad);
        self.history[self.next] = heading_rad;
        self.next = (self.next + 1) % n;
        self.len = (self.len + 1).min(n);
        straight
    }
}

/// Capacity of [`FootprintLine`].
pub const MAX_LINE_FOOTPRINTS: usize = 8;

/// The straight-stretch test on footprints: the last `n` footprints (this one included) lie on
/// a line to within `max_lateral_m`. A curve, a weave or a side-step moves a footprint off the
/// line through its neighbours, while stride-to-stride direction changes alone hardly tell a
/// curve of a few degrees a stride from direction noise. Fixed capacity, no allocation.
#[derive(Debug, Clone, Copy)]
pub struct FootprintLine {
    xy: [[f64; 2]; MAX_LINE_FOOTPRINTS],
    n: usize,
    len: usize,
    next: usize,
    max_lateral_m: f64,
}

impl FootprintLine {
    /// Over `n` footprints (clamped to 2..=[`MAX_LINE_FOOTPRINTS`]).
    pub fn new(n: usize, max_lateral_m: f64) -> Self {
        Self {
            xy: [[0.0; 2]; MAX_LINE_FOOTPRINTS],
            n: n.clamp(2, MAX_LINE_FOOTPRINTS),
            len: 0,
            next: 0,
            max_lateral_m,
        }
    }

    /// Forgets every footprint recorded.
    pub fn clear(&mut self) {
        self.len = 0;
        self.next = 0;
    }

    /// Records a footprint; `Some(true)` when the last `n` lie on a line, `Some(false)` when
    /// they do not, `None` until `n` footprints are known.
    pub fn push(&mut self, xy: [f64; 2]) -> Option<bool> {
        self.xy[self.next] = xy;
        self.next = (self.next + 1) % self.n;
        self.len = (self.len + 1).min(self.n);
        (self.len == self.n).then(|| self.lateral_m() <= self.max_lateral_m)
    }

    /// Largest distance of a footprint from the total-least-squares line through them, m.
    pub fn lateral_m(&self) -> f64 {
        let pts = &self.xy[..self.len];
        let k = pts.len().max(1) as f64;
        let (mx, my) = (
            pts.iter().map(|p| p[0]).sum::<f64>() / k,
            pts.iter().map(|p| p[1]).sum::<f64>() / k,
        );
        let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
        for p in pts {
            let (dx, dy) = (p[0] - mx, p[1] - my);
            sxx += dx * dx;
            syy += dy * dy;
            sxy += dx * dy;
        }
        // Direction of the principal axis; the normal is perpendicular to it.
        let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let (nx, ny) = (-theta.sin(), theta.cos());
        pts.iter()
            .map(|p| ((p[0] - mx) * nx + (p[1] - my) * ny).abs())
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn footprints_on_a_line_pass_and_a_curve_or_a_weave_does_not() {
        let mut line = FootprintLine::new(4, 0.05);
        // A straight walk at 30° with 2 cm of lateral scatter.
        let dir = 30f64.to_radians();
        let mut got = Vec::new();
        for (k, lat) in [0.0, 0.02, -0.02, 0.01, -0.01].iter().enumerate() {
            let s = 1.4 * k as f64;
            got.push(line.push([
                s * dir.cos() - lat * dir.sin(),
                s * dir.sin() + lat * dir.cos(),
            ]));
        }
        assert_eq!(got, [None, None, None, Some(true), Some(true)]);
        // A weave: 0.5 m to the side on the next stride.
        let s = 1.4 * 5.0;
        assert_eq!(
            line.push([
                s * dir.cos() - 0.5 * dir.sin(),
                s * dir.sin() + 0.5 * dir.cos()
            ]),
            Some(false)
        );
        // A curve: 5° more on every stride (a 16 m radius).
        let mut curve = FootprintLine::new(4, 0.05);
        let (mut p, mut h) = ([0.0, 0.0], 0.0f64);
        let mut last = None;
        for _ in 0..6 {
            last = curve.push(p);
            h += 5f64.to_radians();
            p = [p[0] + 1.4 * h.cos(), p[1] + 1.4 * h.sin()];
        }
        assert_eq!(last, Some(false), "lateral {}", curve.lateral_m());
    }

    #[test]
    fn grid_associates_psi_or_psi_plus_pi() {
        let aid = HeadingAid::Grid {
            grid_rad: 0.0,
            step_rad: PI,
        };
        let gate = 20f64.to_radians();
        assert_eq!(aid.associate([0.0; 2], 5f64.to_radians(), gate), Ok(0.0));
        let back = aid.associate([0.0; 2], 170f64.to_radians(), gate).unwrap();
        assert!((wrap_pi(back - PI)).abs() < 1e-12);
        let back2 = aid.associate([0.0; 2], -175f64.to_radians(), gate).unwrap();
        assert!((wrap_pi(back2 - PI)).abs() < 1e-12);
        assert_eq!(
            aid.associate([0.0; 2], 90f64.to_radians(), gate),
            Err(Rejection::OutsideGate)
        );
        let grid90 = HeadingAid::Grid {
            grid_rad: 10f64.to_radians(),
            step_rad: PI / 2.0,
        };
        let d = grid90
            .associate([0.0; 2], 95f64.to_radians(), gate)
            .unwrap();
        assert!((d - 100f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn map_association_needs_a_corridor() {
        let map = CorridorMap {
            corridors: vec![Corridor {
                name: "main".into(),
                from_m: [0.0, 0.0],
                to_m: [39.0, 0.0],
                width_m: 2.4,
            }],
        };
        let aid = HeadingAid::Map(map);
        let gate = 15f64.to_radians();
        assert_eq!(aid.associate([10.0, 1.0], 0.1, gate), Ok(0.0));
        assert!((aid.associate([10.0, -1.0], 3.1, gate).unwrap().abs() - PI).abs() < 1e-12);
        assert_eq!(
            aid.associate([10.0, 1.3], 0.0, gate),
            Err(Rejection::OutsideMap)
        );
        assert_eq!(
            aid.associate([40.0, 0.0], 0.0, gate),
            Err(Rejection::OutsideMap)
        );
        assert_eq!(
            aid.associate([5.0, 0.0], 1.0, gate),
            Err(Rejection::OutsideGate)
        );
    }

    #[test]
    fn a_junction_lists_every_corridor_direction_once() {
        let corridor = |name: &str, from_m, to_m| Corridor {
            name: name.into(),
            from_m,
            to_m,
            width_m: 2.0,
        };
        let aid = HeadingAid::Map(CorridorMap {
            corridors: vec![
                corridor("east-west", [-20.0, 0.0], [20.0, 0.0]),
                // Overlapping and parallel to the first: no new direction.
                corridor("east-west again", [-5.0, 0.5], [5.0, 0.5]),
                corridor("north-south", [0.0, -20.0], [0.0, 20.0]),
                // The east-west corridor's next segment, drawn 0.3° off it, overlapping it.
                corridor("east-west on", [15.0, 0.0], [40.0, 0.13]),
            ],
        });
        let gate = 15f64.to_radians();
        // Away from the junction: one corridor's ψ and ψ + π.
        assert_eq!(
            aid.associate_among([10.0, 0.0], 0.1, gate),
            Ok((0.0, Candidates::Spaced { spacing_rad: PI }))
        );
        // Where the two segments of the east-west corridor overlap: still one corridor.
        let (dir, candidates) = aid.associate_among([17.0, 0.0], 0.01, gate).unwrap();
        assert!(dir.abs() < 0.01, "{dir}");
        assert_eq!(candidates, Candidates::Spaced { spacing_rad: PI });
        // At the junction: four directions, the associated one (north) first.
        let (dir, candidates) = aid.associate_among([0.2, 0.2], 1.5, gate).unwrap();
        assert!((dir - PI / 2.0).abs() < 1e-12);
        let Candidates::Listed { offsets_rad, n } = candidates else {
            panic!("{candidates:?}");
        };
        let mut offsets_deg: Vec<f64> = offsets_rad[..usize::from(n)]
            .iter()
            .map(|o| o.to_degrees().round())
            .map(|d| if d == -180.0 { 180.0 } else { d })
            .collect();
        assert_eq!(offsets_deg[0], 0.0);
        offsets_deg.sort_by(f64::total_cmp);
        assert_eq!(offsets_deg, [-90.0, 0.0, 90.0, 180.0]);
    }

    #[test]
    fn straight_walk_needs_history_and_small_changes() {
        let mut s = StraightWalk::new(2, 10f64.to_radians());
        assert!(!s.push(0.0));
        assert!(!s.push(0.02));
        assert!(s.push(-0.03));
        assert!(!s.push(0.5)); // a turn
        assert!(!s.push(0.5)); // the turn is still in the look-back
        assert!(s.push(0.52));
        // across the ±π seam
        let mut t = StraightWalk::new(1, 10f64.to_radians());
        t.push(PI - 0.01);
        assert!(t.push(-PI + 0.01));
    }
}
