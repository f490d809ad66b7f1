//! Keyframes: a sampler's keys and how it fills in between them, the property a channel drives,
//! and the clips that play channels together, evaluated as the glTF 2.0 specification writes it.

use crate::error::InputError;
use glam::Quat;

/// How a sampler fills in between its keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The previous key's value until the next key.
    Step,
    /// Straight lines between keys (great arcs for rotations).
    Linear,
    /// A cubic Hermite spline through the keys, with an in- and an out-tangent at each.
    CubicSpline,
}

/// The keyframes of one animated property.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampler {
    /// Key times in seconds, finite and strictly increasing (at least one).
    pub times: Vec<f32>,
    /// `width` floats per key; CUBICSPLINE keys hold an in-tangent, the value and an out-tangent,
    /// `3 * width` floats.
    pub values: Vec<f32>,
    /// Floats in one value: 3 for a translation or scale, 4 for a rotation, a weight per target.
    pub width: usize,
    /// How values between keys are found.
    pub interpolation: Interpolation,
}

impl Sampler {
    /// Checks the invariants [`Sampler::sample`] relies on; the error names what is wrong.
    pub fn validate(&self) -> Result<(), InputError> {
        if self.times.is_empty() {
            return Err(InputError::new("no keys"));
        }
        if let Some(k) = self.times.iter().position(|t| !t.is_finite()) {
            return Err(InputError::new(format!("key time {k} is not finite")));
        }
        if let Some(k) = self.times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(InputError::new(format!(
                "key times must increase: key {} at {} s follows {} s",
                k + 1,
                self.times[k + 1],
                self.times[k]
            )));
        }
        let per_key = self.width
            * if self.interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
        if self.values.len() != self.times.len() * per_key {
            return Err(InputError::new(format!(
                "{} output values for {} keys of {per_key}",
                self.values.len(),
                self.times.len()
            )));
        }
        if let Some(v) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(InputError::new(format!("output value {v} is not finite")));
        }
        Ok(())
    }

    /// The time of the last key: where the property stops changing.
    pub fn end(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// The value at `t` into `out` (`width` floats); a rotation (`width` 4) is interpolated on the
    /// sphere where LINEAR and normalized.
    pub fn sample(&self, t: f32, rotation: bool, out: &mut [f32]) {
        let w = self.width;
        let cubic = self.interpolation == Interpolation::CubicSpline;
        // A key's value: the middle third of a cubic key.
        let value = |k: usize| {
            let start = if cubic { (3 * k + 1) * w } else { k * w };
            &self.values[start..start + w]
        };
        let last = self.times.len() - 1;
        // The key at or before t, clamped to the first and last.
        let next = self.times.partition_point(|&key| key <= t);
        if next == 0 || next > last {
            out.copy_from_slice(value(if next == 0 { 0 } else { last }));
        } else {
            let k = next - 1;
            let span = self.times[k + 1] - self.times[k];
            let s = (t - self.times[k]) / span;
            match self.interpolation {
                Interpolation::Step => out.copy_from_slice(value(k)),
                Interpolation::Linear if rotation => {
                    let a = Quat::from_slice(value(k));
                    let b = Quat::from_slice(value(k + 1));
                    slerp(a, b, s).write_to_slice(out);
                }
                Interpolation::Linear => {
                    for ((o, a), b) in out.iter_mut().zip(value(k)).zip(value(k + 1)) {
                        *o = a + (b - a) * s;
                    }
                }
                Interpolation::CubicSpline => {
                    let out_tangent = &self.values[(3 * k + 2) * w..(3 * k + 3) * w];
                    let in_tangent = &self.values[3 * (k + 1) * w..(3 * (k + 1) + 1) * w];
                    let (s2, s3) = (s * s, s * s * s);
                    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                    let h10 = s3 - 2.0 * s2 + s;
                    let h01 = -2.0 * s3 + 3.0 * s2;
                    let h11 = s3 - s2;
                    for c in 0..w {
                        out[c] = h00 * value(k)[c]
                            + h10 * span * out_tangent[c]
                            + h01 * value(k + 1)[c]
                            + h11 * span * in_tangent[c];
                    }
                }
            }
        }
        if rotation {
            let q = Quat::from_slice(out);
            let length = q.length();
            let q = if length > 0.0 { q / length } else { Quat::IDENTITY };
            q.write_to_slice(out);
        }
    }
}

/// Spherical interpolation along the shorter arc, as the glTF specification writes it; nearly
/// equal rotations are interpolated linearly (normalized by the caller).
fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    let mut dot = a.dot(b);
    let b = if dot < 0.0 {
        dot = -dot;
        -b
    } else {
        b
    };
    if dot > 0.9995 {
        return a + (b - a) * s;
    }
    let angle = dot.acos();
    let sin = angle.sin();
    a * (((1.0 - s) * angle).sin() / sin) + b * ((s * angle).sin() / sin)
}

/// What a channel animates on its node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// The node's translation.
    Translation,
    /// The node's rotation.
    Rotation,
    /// The node's scale.
    Scale,
    /// The morph target weights of the node's mesh.
    Weights,
}

/// One channel of a clip: a node's path, and the sampler that drives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The node the channel moves.
    pub node: usize,
    /// Which of its properties.
    pub path: Path,
    /// The keyframes.
    pub sampler: Sampler,
}

/// One animation of a file: channels that play together.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// The file's name for it, where it has one.
    pub name: Option<String>,
    /// The channels.
    pub channels: Vec<Channel>,
}

impl Clip {
    /// Seconds from 0 to the last key of any channel.
    pub fn duration(&self) -> f32 {
        self.channels.iter().map(|c| c.sampler.end()).fold(0.0, f32::max)
    }
}
