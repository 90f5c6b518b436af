//! Eight lanes of the path tracer's vertex arithmetic: glam's `Vec3`
//! operations, the shading frame, the cosine warp, the ray offset and the
//! power heuristic, each written with the scalar code's operations in the
//! scalar code's order, so that a lane's result is the scalar one bit for
//! bit (IEEE arithmetic rounds alike in a SIMD lane and a scalar register).
//! The unit tests compare each against its scalar original.

use crate::bvh::LANES;
use glam::Vec3;
use std::f32::consts::PI;
use wide::f32x8;

/// One number per lane.
pub(super) type Lanes = [f32; LANES];
/// A vector per lane, as three arrays of coordinates.
pub(super) type Lanes3 = [Lanes; 3];

/// A lane mask from the low eight bits of `bits`.
#[inline(always)]
pub(super) fn lane_mask(bits: u32) -> f32x8 {
    let all = f32::from_bits(u32::MAX);
    f32x8::new(std::array::from_fn(|k| {
        if (bits >> k) & 1 != 0 {
            all
        } else {
            0.0
        }
    }))
}

#[inline(always)]
pub(super) fn set3(a: &mut Lanes3, lane: usize, v: Vec3) {
    a[0][lane] = v.x;
    a[1][lane] = v.y;
    a[2][lane] = v.z;
}

#[inline(always)]
pub(super) fn get3(a: &Lanes3, lane: usize) -> Vec3 {
    Vec3::new(a[0][lane], a[1][lane], a[2][lane])
}

/// Eight vectors, one per lane, with glam's `Vec3` arithmetic in the
/// same order of operations.
#[derive(Clone, Copy)]
pub(super) struct V3 {
    pub x: f32x8,
    pub y: f32x8,
    pub z: f32x8,
}

impl V3 {
    #[inline(always)]
    pub(super) fn zero() -> V3 {
        V3 {
            x: f32x8::ZERO,
            y: f32x8::ZERO,
            z: f32x8::ZERO,
        }
    }

    /// `Vec3::dot`: (x x' + y y') + z z'.
    #[inline(always)]
    pub(super) fn dot(self, o: V3) -> f32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// `f32 * Vec3`.
    #[inline(always)]
    pub(super) fn scale(self, k: f32x8) -> V3 {
        V3 {
            x: k * self.x,
            y: k * self.y,
            z: k * self.z,
        }
    }

    /// `Vec3 / f32`.
    #[inline(always)]
    pub(super) fn div(self, k: f32x8) -> V3 {
        V3 {
            x: self.x / k,
            y: self.y / k,
            z: self.z / k,
        }
    }

    /// `Vec3::max_element`, with glam's comparison.
    #[inline(always)]
    pub(super) fn max_element(self) -> f32x8 {
        let max = |a: f32x8, b: f32x8| a.simd_gt(b).select(a, b);
        max(self.x, max(self.y, self.z))
    }

    pub(super) fn abs(self) -> V3 {
        V3 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// Whether all three coordinates are zero.
    #[inline(always)]
    pub(super) fn is_zero(self) -> f32x8 {
        self.x.simd_eq(f32x8::ZERO) & self.y.simd_eq(f32x8::ZERO) & self.z.simd_eq(f32x8::ZERO)
    }

    #[inline(always)]
    pub(super) fn select(m: f32x8, a: V3, b: V3) -> V3 {
        V3 {
            x: m.select(a.x, b.x),
            y: m.select(a.y, b.y),
            z: m.select(a.z, b.z),
        }
    }
}

impl std::ops::Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl std::ops::Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl std::ops::Mul for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, o: V3) -> V3 {
        V3 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
}

impl std::ops::Neg for V3 {
    type Output = V3;
    #[inline(always)]
    fn neg(self) -> V3 {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

/// `geometry::Frame`, lane by lane.
pub(super) struct Frame {
    pub s: V3,
    pub t: V3,
    pub n: V3,
}

impl Frame {
    /// `Frame::new`: Duff et al.'s branchless basis.
    #[inline(always)]
    pub(super) fn new(n: V3) -> Frame {
        let sign = f32x8::ONE | (n.z & f32x8::splat(-0.0));
        let a = f32x8::splat(-1.0) / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            s: V3 {
                x: f32x8::ONE + sign * n.x * n.x * a,
                y: sign * b,
                z: -sign * n.x,
            },
            t: V3 {
                x: b,
                y: sign + n.y * n.y * a,
                z: -n.y,
            },
            n,
        }
    }

    /// `Frame::to_world`.
    #[inline(always)]
    pub(super) fn to_world(&self, v: V3) -> V3 {
        self.s.scale(v.x) + self.t.scale(v.y) + self.n.scale(v.z)
    }
}

/// `Material::bsdf`'s orientation, lane by lane: whether `wo` is on the
/// geometric normal's side, the geometric normal turned to `wo`'s side,
/// and the shading frame around the shading normal turned likewise (the
/// geometric one where it tilts past `wo`).
#[inline(always)]
pub(super) fn oriented_frame(normal: V3, shading_normal: V3, wo: V3) -> (f32x8, V3, Frame) {
    let outside = wo.dot(normal).simd_ge(f32x8::ZERO);
    let ng = V3::select(outside, normal, -normal);
    let ns = V3::select(outside, shading_normal, -shading_normal);
    let ns = V3::select(ns.dot(wo).simd_le(f32x8::ZERO), ng, ns);
    (outside, ng, Frame::new(ns))
}

/// `CameraPath::scatter`'s Russian roulette, lane by lane, for the lanes
/// of `on`: the throughput after it, and the lanes whose paths it ends.
#[inline(always)]
pub(super) fn roulette(throughput: V3, eta_squared: f32x8, on: f32x8, u: f32x8) -> (V3, f32x8) {
    let survive = (throughput.max_element() * eta_squared).min(f32x8::ONE);
    let dies = on & u.simd_ge(survive);
    (V3::select(on, throughput.div(survive), throughput), dies)
}

/// `warp::cosine_hemisphere`, lane by lane.
#[inline(always)]
pub(super) fn cosine_hemisphere(u: f32x8, v: f32x8) -> V3 {
    // `warp::concentric_disk`.
    let two = f32x8::splat(2.0);
    let a = two * u - f32x8::ONE;
    let b = two * v - f32x8::ONE;
    let centre = a.simd_eq(f32x8::ZERO) & b.simd_eq(f32x8::ZERO);
    let wide = a.abs().simd_gt(b.abs());
    let r = wide.select(a, b);
    let other = wide.select(b, a);
    let (sin, cos) = sin_cos_quarter(f32x8::splat(PI / 4.0) * (other / r));
    let x = centre.select(f32x8::ZERO, r * wide.select(cos, sin));
    let y = centre.select(f32x8::ZERO, r * wide.select(sin, cos));
    let z = (f32x8::ONE - (x * x + y * y)).max(f32x8::ZERO).sqrt();
    V3 { x, y, z }
}

/// `warp::sin_cos_quarter`, lane by lane: the same series.
#[inline(always)]
fn sin_cos_quarter(x: f32x8) -> (f32x8, f32x8) {
    let c = f32x8::splat;
    let x2 = x * x;
    let sin = x
        * (c(1.0)
            + x2 * (c(-1.0 / 6.0)
                + x2 * (c(1.0 / 120.0) + x2 * (c(-1.0 / 5040.0) + x2 * c(1.0 / 362_880.0)))));
    let cos = c(1.0)
        + x2 * (c(-0.5)
            + x2 * (c(1.0 / 24.0)
                + x2 * (c(-1.0 / 720.0) + x2 * (c(1.0 / 40_320.0) + x2 * c(-1.0 / 3_628_800.0)))));
    (sin, cos)
}

/// `ray::offset_origin`, lane by lane.
#[inline(always)]
pub(super) fn offset_origin(p: V3, normal: V3, toward: V3, magnitude: f32x8) -> V3 {
    const RELATIVE: f32 = 1.0 / 65536.0;
    let n = V3::select(normal.dot(toward).simd_lt(f32x8::ZERO), -normal, normal);
    let scale = magnitude
        .max(p.abs().max_element())
        .max(f32x8::splat(f32::MIN_POSITIVE));
    p + n.scale(scale * f32x8::splat(RELATIVE))
}

/// `mis::power_heuristic`, lane by lane, its special cases included.
#[inline(always)]
pub(super) fn power_heuristic(own: f32x8, other: f32x8) -> f32x8 {
    let largest = own.max(other);
    let degenerate = largest.is_nan() | largest.simd_le(f32x8::ZERO) | largest.is_inf();
    let (a, b) = (own / largest, other / largest);
    let weight = a * a / (a * a + b * b);
    let fallback = own.simd_ge(other).select(f32x8::ONE, f32x8::ZERO);
    let weight = degenerate.select(fallback, weight);
    own.is_inf().select(f32x8::ONE, weight)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::mis;
    use crate::sampling::warp;

    /// Eight lanes of `f`'s values, for inputs `k = 0..8` of a run.
    fn lanes(f: impl Fn(usize) -> f32) -> f32x8 {
        f32x8::new(std::array::from_fn(f))
    }

    /// A deterministic spread of numbers in [0, 1).
    fn uniform(i: usize) -> f32 {
        ((i as u32).wrapping_mul(2_654_435_769) >> 8) as f32 / (1 << 24) as f32
    }

    #[test]
    fn cosine_directions_are_the_scalar_warps() {
        // The centre of the square, its edges and a spread of points.
        let special = [0.5, 0.0, 1.0 - f32::EPSILON / 2.0, 0.25, 0.75];
        for run in 0..200 {
            let u = |k: usize| match run {
                0..5 => special[run],
                _ => uniform(16 * run + k),
            };
            let v = |k: usize| match run {
                0..5 => special[(run + k) % 5],
                _ => uniform(16 * run + 8 + k),
            };
            let d = cosine_hemisphere(lanes(u), lanes(v));
            for k in 0..8 {
                let w = warp::cosine_hemisphere(u(k), v(k));
                let got = [d.x, d.y, d.z].map(|c| c.to_array()[k].to_bits());
                assert_eq!(got, w.to_array().map(f32::to_bits), "u {} v {}", u(k), v(k));
            }
        }
    }

    #[test]
    fn frames_and_offsets_are_the_scalar_ones() {
        for run in 0..100 {
            let normal = |k: usize| {
                let axis = [Vec3::X, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
                if run == 0 && k < 4 {
                    return axis[k];
                }
                let i = 24 * run + 3 * k;
                Vec3::new(uniform(i) - 0.5, uniform(i + 1) - 0.5, uniform(i + 2) - 0.5).normalize()
            };
            let n = V3 {
                x: lanes(|k| normal(k).x),
                y: lanes(|k| normal(k).y),
                z: lanes(|k| normal(k).z),
            };
            let frame = Frame::new(n);
            let p = n.scale(f32x8::splat(300.0 * uniform(run)));
            let toward = V3 {
                x: n.y,
                y: n.z,
                z: n.x,
            };
            let offset = offset_origin(p, n, toward, f32x8::splat(1.0));
            for k in 0..8 {
                let lane =
                    |v: V3| Vec3::new(v.x.to_array()[k], v.y.to_array()[k], v.z.to_array()[k]);
                let scalar = crate::geometry::Frame::new(normal(k));
                for (ours, theirs) in [(frame.s, scalar.s), (frame.t, scalar.t)] {
                    assert_eq!(
                        lane(ours).to_array().map(f32::to_bits),
                        theirs.to_array().map(f32::to_bits)
                    );
                }
                let expected =
                    crate::geometry::ray::offset_origin(lane(p), normal(k), lane(toward), 1.0);
                assert_eq!(lane(offset), expected);
            }
        }
    }

    #[test]
    fn power_heuristic_is_the_scalar_one_with_its_edge_cases() {
        let values = [
            0.0,
            -0.0,
            1e-30,
            0.3,
            1.0,
            7.5,
            3e38,
            f32::INFINITY,
            f32::NAN,
        ];
        for &own in &values {
            let ours = power_heuristic(f32x8::splat(own), lanes(|k| values[k]));
            let last = power_heuristic(f32x8::splat(own), f32x8::splat(values[8]));
            for (k, &other) in values.iter().enumerate() {
                let got = if k < 8 {
                    ours.to_array()[k]
                } else {
                    last.to_array()[0]
                };
                let expected = mis::power_heuristic(own, other);
                assert_eq!(got.to_bits(), expected.to_bits(), "own {own} other {other}");
            }
        }
    }
}
