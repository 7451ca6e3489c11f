//! The inextensible heavy cantilever (Euler's elastica under its own weight), as the starting
//! shape of a cantilever solve.
//!
//! Newton from the flat strip meets the whole weight with a step that bends the strip without
//! contracting it, so a stiff membrane sees enormous strains and the solve falls back to a load
//! ramp (the ratio-2e4 fit's 276 mm warp cantilever: 133 Newton iterations in 5 load steps).
//! The elastica bends the strip isometrically into nearly the shape it settles in, so Newton
//! starts at a small, bending-dominated residual.
//!
//! With σ = s/L and λ = qL³/B (q the weight per length, B the flexural rigidity), the angle θ of
//! the centreline below the horizontal solves θ'' = −λ (1 − σ) cos θ, θ(0) = 0 (clamped),
//! θ'(1) = 0 (free end: no moment); solved here by shooting on θ'(0) with classical
//! Runge–Kutta, bisecting on θ'(1), which rises with θ'(0).

use crate::Vec3;

/// Runge–Kutta steps along the length.
const STEPS: usize = 400;

/// The centreline of a heavy elastica: angle and position at `STEPS + 1` equally spaced arc
/// lengths from the clamp.
#[derive(Clone, Debug)]
pub struct HeavyElastica {
    length: f64,
    /// (angle below the horizontal, horizontal distance, drop) at each station
    stations: Vec<(f64, f64, f64)>,
}

impl HeavyElastica {
    /// The elastica of a strip `length` long with weight `load` per length and flexural
    /// rigidity `rigidity` (N·m²); `None` for non-positive or non-finite input.
    pub fn new(length: f64, load: f64, rigidity: f64) -> Option<Self> {
        let lambda = load * length.powi(3) / rigidity;
        if !(length > 0.0 && lambda >= 0.0 && lambda.is_finite()) {
            return None;
        }
        // the hanging strip's curvature θ' falls from θ'(0) to 0 at the free end and θ stays
        // below the vertical. A shot from too small a θ'(0) sees θ' turn negative first, one
        // from too large a θ'(0) turns past the vertical or ends with θ'(1) > 0; θ'(0) = 0 is
        // too small and the linear beam's λ/2 is not (θ'(1) alone has roots on curled branches
        // too: one at a chord angle of −69° for λ = 156)
        let (mut lo, mut hi) = (0.0, 0.5 * lambda + 1e-12);
        let too_far = |path: &[(f64, f64)]| {
            for p in path {
                if p.0 > std::f64::consts::FRAC_PI_2 {
                    return true;
                }
                if p.1 < 0.0 {
                    return false;
                }
            }
            path[STEPS].1 > 0.0
        };
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if too_far(&shoot(lambda, mid)) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let path = shoot(lambda, 0.5 * (lo + hi));
        let h = length / STEPS as f64;
        let mut stations = Vec::with_capacity(path.len());
        let (mut y, mut z) = (0.0, 0.0);
        for (k, &(theta, _)) in path.iter().enumerate() {
            if k > 0 {
                // trapezoidal positions from the angles (the angle is smooth: error O(h²))
                let prev = path[k - 1].0;
                y += 0.5 * h * (prev.cos() + theta.cos());
                z += 0.5 * h * (prev.sin() + theta.sin());
            }
            stations.push((theta, y, z));
        }
        Some(Self { length, stations })
    }

    /// The angle of the chord from the clamp to the free end below the horizontal, degrees
    /// (what ASTM D1388 reads).
    pub fn chord_angle_deg(&self) -> f64 {
        let &(_, y, z) = self.stations.last().expect("stations");
        z.atan2(y).to_degrees()
    }

    /// (horizontal distance, drop) of the point at arc length `s` from the clamp: straight and
    /// level behind the clamp (s < 0), along the free end's tangent past it.
    pub fn at(&self, s: f64) -> (f64, f64) {
        if s <= 0.0 {
            return (s, 0.0);
        }
        let h = self.length / STEPS as f64;
        let t = s / h;
        if t >= STEPS as f64 {
            let (theta, y, z) = self.stations[STEPS];
            let past = s - self.length;
            return (y + past * theta.cos(), z + past * theta.sin());
        }
        let k = t.floor() as usize;
        let w = t - k as f64;
        let (a, b) = (self.stations[k], self.stations[k + 1]);
        (a.1 + w * (b.1 - a.1), a.2 + w * (b.2 - a.2))
    }

    /// A strip's control points laid flat along +y from the clamped edge y = 0 (z = 0, weight
    /// towards −z), rows `spacing` apart, bent onto the elastica: each point keeps its x and
    /// its arc length y. A uniform cubic B-spline's limit point is (P₋ + 4P + P₊)/6, so points
    /// placed on the curve leave the surface inside it by h²Q''/6; each point is moved out by
    /// that much first (P = Q − (Q₋ − 2Q + Q₊)/6), which leaves O(h⁴): stiff yarns see the
    /// difference as strain.
    pub fn bend(&self, rest: &[Vec3], spacing: f64) -> Vec<Vec3> {
        rest.iter()
            .map(|p| {
                let q = |s: f64| self.at(s);
                let (a, b, c) = (q(p[1] - spacing), q(p[1]), q(p[1] + spacing));
                let y = b.0 - (a.0 - 2.0 * b.0 + c.0) / 6.0;
                let drop = b.1 - (a.1 - 2.0 * b.1 + c.1) / 6.0;
                [p[0], y, p[2] - drop]
            })
            .collect()
    }
}

/// (θ, θ') at every station for θ'(0) = `slope`, in units of the length.
fn shoot(lambda: f64, slope: f64) -> Vec<(f64, f64)> {
    let h = 1.0 / STEPS as f64;
    let f =
        |sigma: f64, (theta, dtheta): (f64, f64)| (dtheta, -lambda * (1.0 - sigma) * theta.cos());
    let mut state = (0.0, slope);
    let mut out = Vec::with_capacity(STEPS + 1);
    out.push(state);
    for k in 0..STEPS {
        let s = k as f64 * h;
        let k1 = f(s, state);
        let k2 = f(
            s + 0.5 * h,
            (state.0 + 0.5 * h * k1.0, state.1 + 0.5 * h * k1.1),
        );
        let k3 = f(
            s + 0.5 * h,
            (state.0 + 0.5 * h * k2.0, state.1 + 0.5 * h * k2.1),
        );
        let k4 = f(s + h, (state.0 + h * k3.0, state.1 + h * k3.1));
        state = (
            state.0 + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
            state.1 + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
        );
        out.push(state);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::HeavyElastica;

    #[test]
    fn the_d1388_overhang_droops_to_the_elastica_angle() {
        // overhang twice the bending length (λ = 8): 41.4873° (the value tests/cantilever.rs
        // checks the shell against; the project's shell benchmark notes)
        let e = HeavyElastica::new(0.2, 1.0, 0.2f64.powi(3) / 8.0).unwrap();
        assert!(
            (e.chord_angle_deg() - 41.4873).abs() < 1e-3,
            "{}",
            e.chord_angle_deg()
        );
    }

    #[test]
    fn a_long_strip_hangs_without_curling() {
        // the chord angle rises towards 90° with the overhang (λ = 20, 156, 1250)
        let angles: Vec<f64> = [0.1, 0.2, 0.4]
            .iter()
            .map(|&l| {
                HeavyElastica::new(l, 0.0254, 1.458e-6)
                    .unwrap()
                    .chord_angle_deg()
            })
            .collect();
        assert!(angles.windows(2).all(|w| w[1] > w[0]), "{angles:?}");
        assert!(angles[0] > 45.0 && angles[2] < 90.0, "{angles:?}");
    }

    #[test]
    fn a_light_load_gives_the_linear_beam_deflection() {
        // tip drop q L⁴ / (8 B) for λ ≪ 1 (Euler–Bernoulli), relative error O(λ²) = 1e-10
        // here, plus the trapezoidal positions' O(h²) = 6e-6 (2.1e-6 in practice)
        let (l, q, b) = (0.1, 1.0, 1.0e2);
        let e = HeavyElastica::new(l, q, b).unwrap();
        let drop = e.at(l).1;
        let linear = q * l.powi(4) / (8.0 * b);
        assert!((drop - linear).abs() < 1e-5 * linear, "{drop} vs {linear}");
    }

    #[test]
    fn the_centreline_keeps_its_length() {
        // the D1388 overhang (λ = 8); the polyline through the stations is shorter than the arc
        // by O(h²)
        let e = HeavyElastica::new(0.3, 2.0, 2.0 * 0.3f64.powi(3) / 8.0).unwrap();
        let n = 1000;
        let mut len = 0.0;
        let mut last = e.at(0.0);
        for k in 1..=n {
            let p = e.at(0.3 * k as f64 / n as f64);
            len += (p.0 - last.0).hypot(p.1 - last.1);
            last = p;
        }
        assert!((len - 0.3).abs() < 1e-5, "{len}");
        assert!(HeavyElastica::new(0.3, 2.0, 0.0).is_none());
    }
}
