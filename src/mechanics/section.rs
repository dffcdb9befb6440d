//! Cross-sections: their dimensions and their properties for bending about the horizontal
//! axis. Coordinates are (y, z): y across the beam, z up, origin at the centroid. The outline
//! a beam is meshed from is geometry's business (`geometry::outline`).

use serde::Serialize;

/// A beam's cross-section, tagged by `shape`; dimensions in metres, width across the beam (y) and
/// height in the bending plane (z, up).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum Section {
    /// Solid rectangle.
    Rectangle {
        /// Width across the beam, metres.
        width: f64,
        /// Height (depth in the bending plane), metres.
        height: f64,
    },
    /// Doubly symmetric I/H: flange width, overall height, flange and web thicknesses.
    ISection {
        /// Flange width, metres.
        width: f64,
        /// Overall height, outside of flange to outside of flange, metres.
        height: f64,
        /// Flange thickness t_f, metres (less than half the height).
        flange: f64,
        /// Web thickness t_w, metres (less than the flange width).
        web: f64,
    },
    /// Rectangular hollow section with uniform wall.
    HollowBox {
        /// Outer width across the beam, metres.
        width: f64,
        /// Outer height, metres.
        height: f64,
        /// Wall thickness, metres (less than half the smaller outer dimension).
        wall: f64,
    },
    /// Circular hollow section (tube).
    CircularHollow {
        /// Outer diameter, metres.
        diameter: f64,
        /// Wall thickness, metres (less than the outer radius).
        wall: f64,
    },
}

/// Properties of a cross-section for bending about its horizontal centroidal axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SectionProperties {
    /// Cross-sectional area A, m².
    pub area: f64,
    /// Second moment of area I about the horizontal centroidal axis, m⁴.
    pub second_moment: f64,
    /// Timoshenko shear coefficient κ (shear area = κA).
    pub shear_coefficient: f64,
    /// Distance c from the centroid to the extreme fibre, metres (half the section height).
    pub extreme_fibre: f64,
}

impl Section {
    /// Overall width across the beam (the outer diameter for a tube), metres.
    pub fn width(&self) -> f64 {
        match *self {
            Section::Rectangle { width, .. }
            | Section::ISection { width, .. }
            | Section::HollowBox { width, .. } => width,
            Section::CircularHollow { diameter, .. } => diameter,
        }
    }

    /// Overall height (the outer diameter for a tube), metres.
    pub fn height(&self) -> f64 {
        match *self {
            Section::Rectangle { height, .. }
            | Section::ISection { height, .. }
            | Section::HollowBox { height, .. } => height,
            Section::CircularHollow { diameter, .. } => diameter,
        }
    }

    /// Checks the dimensions; the message names the offending one and its value.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, x: f64| {
            if x > 0.0 && x.is_finite() {
                Ok(())
            } else {
                Err(format!("section {name} = {x} must be positive (metres)"))
            }
        };
        let thinner = |name: &str, t: f64, limit: f64, what: &str| {
            if t < limit {
                Ok(())
            } else {
                Err(format!(
                    "section {name} = {t} m must be less than {what} ({limit} m)"
                ))
            }
        };
        match *self {
            Section::Rectangle { width, height } => {
                positive("width", width).and(positive("height", height))
            }
            Section::ISection {
                width,
                height,
                flange,
                web,
            } => {
                positive("width", width)?;
                positive("height", height)?;
                positive("flange", flange)?;
                positive("web", web)?;
                thinner("flange", flange, height / 2.0, "half the height")?;
                thinner("web", web, width, "the flange width")
            }
            Section::HollowBox {
                width,
                height,
                wall,
            } => {
                positive("width", width)?;
                positive("height", height)?;
                positive("wall", wall)?;
                thinner(
                    "wall",
                    wall,
                    width.min(height) / 2.0,
                    "half the smaller outer dimension",
                )
            }
            Section::CircularHollow { diameter, wall } => {
                positive("diameter", diameter)?;
                positive("wall", wall)?;
                thinner("wall", wall, diameter / 2.0, "the radius")
            }
        }
    }

    /// Area, second moment, shear coefficient κ and extreme-fibre distance; Poisson's ratio
    /// `poisson` enters κ of the rectangle and the tube.
    pub fn properties(&self, poisson: f64) -> SectionProperties {
        let nu = poisson;
        let (area, second_moment, shear_coefficient) = match *self {
            // Cowper (1966) for the rectangle.
            Section::Rectangle {
                width: b,
                height: h,
            } => (
                b * h,
                b * h.powi(3) / 12.0,
                10.0 * (1.0 + nu) / (12.0 + 11.0 * nu),
            ),
            // Shear carried by the web: κ = A_web/A.
            Section::ISection {
                width: b,
                height: h,
                flange: tf,
                web: tw,
            } => {
                let area = 2.0 * b * tf + (h - 2.0 * tf) * tw;
                (
                    area,
                    (b * h.powi(3) - (b - tw) * (h - 2.0 * tf).powi(3)) / 12.0,
                    (h - 2.0 * tf) * tw / area,
                )
            }
            // EN 1993-1-1 §6.2.6 shear area of a hollow rectangle loaded parallel to its height: A·h/(b + h).
            Section::HollowBox {
                width: b,
                height: h,
                wall: t,
            } => {
                let (bi, hi) = (b - 2.0 * t, h - 2.0 * t);
                (
                    b * h - bi * hi,
                    (b * h.powi(3) - bi * hi.powi(3)) / 12.0,
                    h / (b + h),
                )
            }
            // Cowper (1966) for a hollow circle, m = inner/outer diameter.
            Section::CircularHollow {
                diameter: d,
                wall: t,
            } => {
                let di = d - 2.0 * t;
                let m2 = (di / d).powi(2);
                let kappa = 6.0 * (1.0 + nu) * (1.0 + m2).powi(2)
                    / ((7.0 + 6.0 * nu) * (1.0 + m2).powi(2) + (20.0 + 12.0 * nu) * m2);
                let pi = std::f64::consts::PI;
                (
                    pi / 4.0 * (d * d - di * di),
                    pi / 64.0 * (d.powi(4) - di.powi(4)),
                    kappa,
                )
            }
        };
        SectionProperties {
            area,
            second_moment,
            shear_coefficient,
            extreme_fibre: self.height() / 2.0,
        }
    }
}

/// One section of each kind, for tests across the crate (the I-section is an IPE 300:
/// 150 × 300, tf 10.7, tw 7.1, root fillets ignored).
#[cfg(test)]
pub fn examples() -> Vec<Section> {
    vec![
        Section::Rectangle {
            width: 0.3,
            height: 0.5,
        },
        Section::ISection {
            width: 0.150,
            height: 0.300,
            flange: 0.0107,
            web: 0.0071,
        },
        Section::HollowBox {
            width: 0.2,
            height: 0.3,
            wall: 0.01,
        },
        Section::CircularHollow {
            diameter: 0.3239,
            wall: 0.01,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn properties_match_handbook_values() {
        for s in examples() {
            let p = s.properties(0.3);
            assert!(
                p.shear_coefficient > 0.0 && p.shear_coefficient <= 1.0,
                "{s:?}"
            );
        }
        // IPE 300 tables (with 15 mm root fillets): A = 53.8 cm², I = 8356 cm⁴. The four fillets
        // add 4(1 − π/4)r² = 1.93 cm² of area and about 4 % of I, which this section omits.
        let ipe = examples()[1].properties(0.3);
        assert!(
            (ipe.area * 1e4 - (53.8 - 1.93)).abs() < 0.05,
            "{}",
            ipe.area * 1e4
        );
        assert!(
            (ipe.second_moment * 1e8 / 8356.0 - 0.96).abs() < 0.01,
            "{}",
            ipe.second_moment * 1e8
        );
        // Cowper's values: rectangle 0.8497, thin tube → 2(1+ν)/(4+3ν) = 0.5306.
        assert!((examples()[0].properties(0.3).shear_coefficient - 0.8497).abs() < 1e-4);
        let thin = Section::CircularHollow {
            diameter: 1.0,
            wall: 1e-4,
        }
        .properties(0.3);
        assert!((thin.shear_coefficient - 2.6 / 4.9).abs() < 1e-3);
    }

    #[test]
    fn bad_dimensions_are_named() {
        let e = Section::CircularHollow {
            diameter: 0.2,
            wall: 0.15,
        }
        .validate()
        .unwrap_err();
        assert!(e.contains("wall = 0.15"), "{e}");
        assert!(
            Section::ISection {
                width: 0.1,
                height: 0.2,
                flange: 0.01,
                web: f64::NAN
            }
            .validate()
            .is_err()
        );
    }
}
