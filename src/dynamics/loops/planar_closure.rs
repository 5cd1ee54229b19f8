//! The loops' translation rows of a planar mechanism evaluated so that their round-off does
//! not grow with the chain's extent. The spatial rows (`rows`) place each body by composing
//! its parent's pose with its joint's: every product of rotations rounds, the rounding turns
//! the whole chain beyond it, and a loop's closing point carries the sum of those turns times
//! their lever arms. On a necklace of 1,000 rods of 1 m (a chain some 900 m across) the rows so
//! evaluated were up to 2.4e-12 m off their exact value (50 digits), where the state's own
//! closure was 5e-14; summing the positions with compensated sums alone left 1.7e-12, since the
//! rotations' products, not the sums, were the source.
//!
//! In the plane a body's orientation is the sum of its joints' angles: summed as an unevaluated
//! pair (Knuth's TwoSum, Knuth 1998, TAOCP vol. 2, §4.2.2; Dekker 1971 for the product's error,
//! by a fused multiply-add), each body's rotation is taken from its own angle, to within one
//! rounding of its cosine and sine, and never from its parent's rotation; the positions along
//! the tree are summed with compensated sums (Ogita, Rump and Oishi 2005, "Accurate sum and dot
//! product", Sum2). A term's rounding then moves the closing point by about the unit round-off
//! times that term's own length, whatever lies beyond it: on the same necklace the rows are
//! within 5e-15 of their exact value. The rotation rows are left to the spatial rows: a turn's
//! rounding has no lever arm there.
//!
//! Only loops whose cycle holds more than `LONG_CYCLE` joints are evaluated so: on shorter
//! ones the spatial rows' round-off is already that of a few terms, and their last bits are
//! kept. A row of two four-bars passing its flat configurations at dopri5 1e-12 is sensitive to
//! them: with its loops (cycles of four joints) evaluated in the plane, its energy drifted
//! 1.18e-9 instead of below 1e-9.

use nalgebra::Vector2;

use super::rows::Constraints;
use crate::dynamics::model::Model;
use crate::dynamics::planar::model::{PlanarJointKind, PlanarLoopKind, PlanarModel};

/// The number of tree joints on the cycle of a loop between `first` and `second`: on either
/// body's path to earth and not on both.
fn cycle_length(model: &Model, first: usize, second: usize) -> usize {
    let on_first: Vec<usize> = model.path_to_earth(first).collect();
    let on_second: Vec<usize> = model.path_to_earth(second).collect();
    // The bodies on both paths are the two paths' common end, from where they meet to earth:
    // counted from earth in a time linear in the paths (a ladder's paths are as long as it is).
    let shared = (on_first.iter().rev())
        .zip(on_second.iter().rev())
        .take_while(|(a, b)| a == b)
        .count();
    on_first.len() + on_second.len() - 2 * shared
}

/// A number and its rounding error, unevaluated: the pair's sum is the value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Pair {
    high: f64,
    low: f64,
}

impl Pair {
    /// a + b exactly, as a pair (TwoSum).
    #[inline]
    fn sum(a: f64, b: f64) -> Pair {
        let high = a + b;
        let b_virtual = high - a;
        let low = (a - (high - b_virtual)) + (b - b_virtual);
        Pair { high, low }
    }

    /// a · b exactly, as a pair (Dekker's product, by a fused multiply-add).
    #[inline]
    fn product(a: f64, b: f64) -> Pair {
        let high = a * b;
        Pair {
            high,
            low: a.mul_add(b, -high),
        }
    }

    /// This plus `x`, the new rounding error added to the low part (Sum2).
    #[inline]
    fn add(self, x: f64) -> Pair {
        let s = Pair::sum(self.high, x);
        Pair {
            high: s.high,
            low: self.low + s.low,
        }
    }

    /// This plus another pair, to the same accuracy.
    #[inline]
    fn add_pair(self, other: Pair) -> Pair {
        let s = self.add(other.high);
        Pair {
            low: s.low + other.low,
            ..s
        }
    }

    fn value(self) -> f64 {
        self.high + self.low
    }
}

/// A point of the fixed plane, each coordinate a pair.
#[derive(Clone, Copy, Debug, Default)]
struct Point {
    x: Pair,
    y: Pair,
}

impl Point {
    /// This point moved by `v`.
    #[inline]
    fn moved(self, v: Vector2<f64>) -> Point {
        Point {
            x: self.x.add(v.x),
            y: self.y.add(v.y),
        }
    }
}

/// A turn by an angle given as a pair: its cosine and sine, to one rounding of each.
#[derive(Clone, Copy, Debug)]
struct Turn {
    cos: f64,
    sin: f64,
}

impl Turn {
    fn of(angle: Pair) -> Turn {
        // cos(h + l) = cos h − l sin h and sin(h + l) = sin h + l cos h to within l², with
        // |l| at most half an ulp of h.
        let (sin, cos) = angle.high.sin_cos();
        Turn {
            cos: cos - angle.low * sin,
            sin: sin + angle.low * cos,
        }
    }

    #[inline]
    fn rotate(&self, v: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(
            self.cos * v.x - self.sin * v.y,
            self.sin * v.x + self.cos * v.y,
        )
    }
}

/// A body's planar frame in the fixed plane, each part accurate to about the unit round-off
/// times the terms summed into it.
#[derive(Clone, Copy, Debug)]
struct Placed {
    angle: Pair,
    turn: Turn,
    origin: Point,
}

impl Placed {
    const FIXED: Placed = Placed {
        angle: Pair {
            high: 0.0,
            low: 0.0,
        },
        turn: Turn { cos: 1.0, sin: 0.0 },
        origin: Point {
            x: Pair {
                high: 0.0,
                low: 0.0,
            },
            y: Pair {
                high: 0.0,
                low: 0.0,
            },
        },
    };

    /// The point `p` of this frame in the fixed plane.
    fn point(&self, p: &Vector2<f64>) -> Point {
        self.origin.moved(self.turn.rotate(p))
    }
}

/// Loops whose cycle (the tree joints from each of its two bodies up to their last common
/// ancestor) holds more joints than this are evaluated in the plane: the spatial rows'
/// round-off grows about as the joints' count to the power 1.5 times the longest term (each
/// composition's rounding turns the rest of the cycle), the planar rows' as its square root.
pub const LONG_CYCLE: usize = 8;

/// How a unit round-off of each term summed into a loop's translation rows adds up: those
/// terms' lengths (joint pivots and origins, loop points) in quadrature, in metres.
pub type Spread = f64;

/// The loops' translation rows of a planar mechanism whose plane is normal to a fixed axis,
/// evaluated in its planar form (see the module's documentation).
#[derive(Clone, Debug)]
pub struct PlanarClosure {
    planar: PlanarModel,
    /// Per loop, its second frame's origin in the second body's planar frame.
    second: Vec<Vector2<f64>>,
    /// Per loop, the terms' lengths in quadrature (`Spread`).
    spreads: Vec<Spread>,
    /// Per loop, whether its cycle is long enough to be evaluated here (`LONG_CYCLE`).
    long: Vec<bool>,
    /// Per body (0 is earth), its planar frame at the positions last evaluated.
    placed: Vec<Placed>,
}

impl PlanarClosure {
    /// For `model`'s planar form; `None` when its plane is not normal to a fixed axis (the
    /// rows in the plane are then combinations of the fixed axes' rows) or none of its loops
    /// has a cycle longer than `LONG_CYCLE`.
    pub fn new(model: &Model, planar: &PlanarModel) -> Option<PlanarClosure> {
        planar.rows?;
        let long: Vec<bool> = (model.loops.iter())
            .map(|joint| cycle_length(model, joint.first_body, joint.second_body) > LONG_CYCLE)
            .collect();
        if !long.contains(&true) {
            return None;
        }
        let second: Vec<Vector2<f64>> = (model.loops.iter())
            .map(|joint| {
                (planar.to_planar[joint.second_body] * joint.second.translation.vector).xy()
            })
            .collect();
        // Each body's terms: its joint's pivots or origin, and those of the joints above it.
        let mut squares = vec![0.0; model.body_count() + 1];
        for joint in &planar.joints {
            let own = match &joint.kind {
                PlanarJointKind::Revolute {
                    pivot_parent,
                    pivot_child,
                    ..
                } => pivot_parent.norm_squared() + pivot_child.norm_squared(),
                PlanarJointKind::Prismatic { origin, .. } | PlanarJointKind::Weld { origin } => {
                    origin.norm_squared()
                }
            };
            squares[joint.child] = squares[joint.parent] + own;
        }
        let spreads = (planar.loops.iter().zip(&second))
            .map(|(closing, second)| {
                let ends = closing.first.norm_squared() + second.norm_squared();
                (squares[closing.first_body] + squares[closing.second_body] + ends).sqrt()
            })
            .collect();
        Some(PlanarClosure {
            planar: planar.clone(),
            second,
            spreads,
            long,
            placed: vec![Placed::FIXED; model.body_count() + 1],
        })
    }

    /// Loop `k`'s `Spread`, if it is evaluated here (`LONG_CYCLE`).
    pub fn spread(&self, k: usize) -> Option<Spread> {
        self.long[k].then(|| self.spreads[k])
    }

    /// Writes the in-plane translation rows of every loop at the positions `q` into
    /// `c.residual`, in place of the spatial rows' values; the other rows are left as they are.
    pub fn translations_into(&mut self, model: &Model, q: &[f64], c: &mut Constraints) {
        for joint in &self.planar.joints {
            let parent = self.placed[joint.parent];
            let coordinate = q.get(joint.q_offset).copied().unwrap_or(0.0);
            self.placed[joint.child] = match &joint.kind {
                PlanarJointKind::Revolute {
                    rate,
                    pivot_parent,
                    pivot_child,
                } => {
                    let angle = parent.angle.add_pair(Pair::product(*rate, coordinate));
                    let turn = Turn::of(angle);
                    let origin = parent.point(pivot_parent).moved(-turn.rotate(pivot_child));
                    Placed {
                        angle,
                        turn,
                        origin,
                    }
                }
                PlanarJointKind::Prismatic { origin, direction } => Placed {
                    origin: parent
                        .point(origin)
                        .moved(parent.turn.rotate(&(direction * coordinate))),
                    ..parent
                },
                PlanarJointKind::Weld { origin } => Placed {
                    origin: parent.point(origin),
                    ..parent
                },
            };
        }
        let [_, (x_row, x_sign), (y_row, y_sign)] = self.planar.rows.expect("checked by `new`");
        for (k, closing) in self.planar.loops.iter().enumerate() {
            if !self.long[k] {
                continue;
            }
            let first = &self.placed[closing.first_body];
            let end = match &closing.kind {
                PlanarLoopKind::Revolute { .. } => first.point(&closing.first),
                PlanarLoopKind::Prismatic { direction } => {
                    let coordinate = q[model.nq + model.loop_offset(k)];
                    first
                        .point(&closing.first)
                        .moved(first.turn.rotate(&(direction * coordinate)))
                }
            };
            let target = self.placed[closing.second_body].point(&self.second[k]);
            let gap_x = target.x.add_pair(Pair {
                high: -end.x.high,
                low: -end.x.low,
            });
            let gap_y = target.y.add_pair(Pair {
                high: -end.y.high,
                low: -end.y.low,
            });
            c.residual[6 * k + x_row] = x_sign * gap_x.value();
            c.residual[6 * k + y_row] = y_sign * gap_y.value();
        }
    }
}
