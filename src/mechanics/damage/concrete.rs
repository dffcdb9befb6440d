//! A reinforced-concrete rectangular section after EN 1992-1-1 (Eurocode 2): the concrete's
//! mean tensile strength and modulus (Table 3.1), the cracking moment, the fully cracked
//! transformed section, crack spacing and width (§7.3.4, Eqs. 7.8, 7.9, 7.11, 7.14) and the
//! curvature of a member between uncracked and fully cracked (§7.4.3, Eq. 7.18). Derivations and
//! the clauses: docs/damage.md.

use serde::Serialize;

/// Modulus of reinforcing steel E_s, Pa (EN 1992-1-1 §3.2.7(4)).
pub const REBAR_E: f64 = 200e9;
/// k1 of Eq. 7.11: high-bond bars.
const K1_HIGH_BOND: f64 = 0.8;
/// k2 of Eq. 7.11: bending.
const K2_BENDING: f64 = 0.5;
/// k3 and k4 of Eq. 7.11, the recommended values (National Annexes may differ).
const K3: f64 = 3.4;
const K4: f64 = 0.425;

/// How a reinforced-concrete beam is reinforced and what concrete it is made of. The bars
/// describe the reinforcement of whichever face is in tension (bottom under sagging, top under
/// hogging); stirrups are not modelled.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Reinforcement {
    /// Characteristic cylinder strength f_ck, Pa (default 30 MPa, C30/37; at most 90 MPa).
    pub fck: f64,
    /// Cover to the longitudinal bars' surface c, metres (default 0.035).
    pub cover: f64,
    /// Bar diameter φ, metres (default 0.016).
    pub bar_diameter: f64,
    /// Number of tension bars (default 3).
    pub bars: u32,
    /// Long-term (sustained) loading: k_t = 0.4 and β = 0.5; otherwise short-term, k_t = 0.6
    /// and β = 1 (default false).
    pub sustained: bool,
}

impl Default for Reinforcement {
    fn default() -> Self {
        Reinforcement {
            fck: 30e6,
            cover: 0.035,
            bar_diameter: 0.016,
            bars: 3,
            sustained: false,
        }
    }
}

/// Mean compressive strength f_cm = f_ck + 8 MPa (Table 3.1).
fn mean_strength(fck: f64) -> f64 {
    fck + 8e6
}

/// Mean axial tensile strength f_ctm, Pa (Table 3.1): 0.30 f_ck^(2/3) up to C50/60,
/// 2.12 ln(1 + f_cm/10) above (strengths in MPa).
pub fn tensile_strength(fck: f64) -> f64 {
    let mpa = fck / 1e6;
    let f = if mpa <= 50.0 {
        0.30 * mpa.powf(2.0 / 3.0)
    } else {
        2.12 * (1.0 + mean_strength(fck) / 1e6 / 10.0).ln()
    };
    f * 1e6
}

/// Secant modulus E_cm = 22 (f_cm/10)^0.3 GPa (Table 3.1, quartzite aggregate).
pub fn concrete_modulus(fck: f64) -> f64 {
    22e9 * (mean_strength(fck) / 1e6 / 10.0).powf(0.3)
}

impl Reinforcement {
    /// Checks every number against what the model covers, naming the parameter and its value.
    pub fn validate(&self, height: f64) -> Result<(), String> {
        if !(self.fck >= 12e6 && self.fck <= 90e6) {
            return Err(format!(
                "reinforcement fck = {} Pa must lie in [12e6, 90e6] (C12/15 to C90/105)",
                self.fck
            ));
        }
        if !(self.bar_diameter > 0.0 && self.bar_diameter < 0.1) {
            return Err(format!(
                "reinforcement bar_diameter = {} m must lie in (0, 0.1)",
                self.bar_diameter
            ));
        }
        if !(self.cover > 0.0 && self.cover + self.bar_diameter < 0.5 * height) {
            return Err(format!(
                "reinforcement cover = {} m must be positive and cover + bar_diameter below half the section height ({} m)",
                self.cover,
                0.5 * height
            ));
        }
        if self.bars == 0 {
            return Err("reinforcement bars = 0: at least one bar is needed".into());
        }
        Ok(())
    }
}

/// A rectangular reinforced-concrete section, solved once: everything the crack and
/// curvature models need, in SI units.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ConcreteSection {
    /// Width b, metres.
    pub width: f64,
    /// Height h, metres.
    pub height: f64,
    /// Effective depth d = h − c − φ/2, metres.
    pub effective_depth: f64,
    /// Tension steel area A_s, m².
    pub steel_area: f64,
    /// Mean tensile strength f_ctm, Pa.
    pub tensile_strength: f64,
    /// Concrete modulus E_cm, Pa.
    pub concrete_modulus: f64,
    /// Modular ratio α_e = E_s / E_cm.
    pub modular_ratio: f64,
    /// Second moment of the uncracked (gross concrete) section I_I, m⁴.
    pub uncracked_inertia: f64,
    /// Second moment of the fully cracked transformed section I_II, m⁴.
    pub cracked_inertia: f64,
    /// Depth of the cracked section's neutral axis from the compression face x, metres.
    pub neutral_axis: f64,
    /// Cracking moment M_cr = f_ctm I_I / (h/2), N·m.
    pub cracking_moment: f64,
    /// Effective tension area ratio ρ_p,eff = A_s / (b h_c,eff).
    pub effective_ratio: f64,
    /// Maximum crack spacing s_r,max, metres (Eq. 7.11, or 7.14 for widely spaced bars).
    pub crack_spacing: f64,
    /// k_t of Eq. 7.9.
    pub kt: f64,
    /// β of Eq. 7.19.
    pub beta: f64,
}

impl ConcreteSection {
    /// The section `width` × `height` with `bars`.
    pub fn new(width: f64, height: f64, bars: &Reinforcement) -> ConcreteSection {
        let (b, h, c, phi) = (width, height, bars.cover, bars.bar_diameter);
        let d = h - c - 0.5 * phi;
        let steel_area = bars.bars as f64 * std::f64::consts::PI * phi * phi / 4.0;
        let ecm = concrete_modulus(bars.fck);
        let ae = REBAR_E / ecm;
        let rho = steel_area / (b * d);
        // Neutral axis of the cracked section: b x²/2 = α_e A_s (d − x), in the form without
        // cancellation for small α_e ρ.
        let x = d * 2.0 / (1.0 + (1.0 + 2.0 / (ae * rho)).sqrt());
        let cracked_inertia = b * x.powi(3) / 3.0 + ae * steel_area * (d - x).powi(2);
        let uncracked_inertia = b * h.powi(3) / 12.0;
        let fctm = tensile_strength(bars.fck);
        let hc_eff = (2.5 * (h - d)).min((h - x) / 3.0).min(h / 2.0);
        let effective_ratio = steel_area / (b * hc_eff);
        let spacing_of_bars = if bars.bars > 1 {
            (b - 2.0 * c - phi) / (bars.bars - 1) as f64
        } else {
            b
        };
        let crack_spacing = if spacing_of_bars <= 5.0 * (c + 0.5 * phi) {
            K3 * c + K1_HIGH_BOND * K2_BENDING * K4 * phi / effective_ratio
        } else {
            1.3 * (h - x)
        };
        let (kt, beta) = if bars.sustained {
            (0.4, 0.5)
        } else {
            (0.6, 1.0)
        };
        ConcreteSection {
            width,
            height,
            effective_depth: d,
            steel_area,
            tensile_strength: fctm,
            concrete_modulus: ecm,
            modular_ratio: ae,
            uncracked_inertia,
            cracked_inertia,
            neutral_axis: x,
            cracking_moment: fctm * uncracked_inertia / (0.5 * h),
            effective_ratio,
            crack_spacing,
            kt,
            beta,
        }
    }

    /// Stress in the tension steel of the fully cracked section under |moment|, Pa.
    pub fn steel_stress(&self, moment: f64) -> f64 {
        self.modular_ratio * moment.abs() * (self.effective_depth - self.neutral_axis)
            / self.cracked_inertia
    }

    /// Mean strain difference ε_sm − ε_cm (Eq. 7.9), at least 0.6 σ_s / E_s.
    fn strain_difference(&self, moment: f64) -> f64 {
        let sigma = self.steel_stress(moment);
        let rho = self.effective_ratio;
        let tension_stiffening =
            self.kt * self.tensile_strength / rho * (1.0 + self.modular_ratio * rho);
        ((sigma - tension_stiffening) / REBAR_E).max(0.6 * sigma / REBAR_E)
    }

    /// Characteristic crack width w_k = s_r,max (ε_sm − ε_cm) under `moment`, metres (Eq. 7.8).
    pub fn crack_width(&self, moment: f64) -> f64 {
        self.crack_spacing * self.strain_difference(moment)
    }

    /// Distribution coefficient ζ = 1 − β (M_cr/M)² (Eq. 7.19), 0 where the section is
    /// uncracked (|M| ≤ M_cr).
    pub fn distribution(&self, moment: f64) -> f64 {
        if moment.abs() <= self.cracking_moment {
            0.0
        } else {
            1.0 - self.beta * (self.cracking_moment / moment).powi(2)
        }
    }

    /// Curvature under `moment` (sign of the moment), Eq. 7.18 applied to curvature:
    /// ζ M/(E I_II) + (1 − ζ) M/(E I_I), with the beam's modulus `e`.
    pub fn curvature(&self, moment: f64, e: f64) -> f64 {
        let zeta = self.distribution(moment);
        moment / e * (zeta / self.cracked_inertia + (1.0 - zeta) / self.uncracked_inertia)
    }

    /// Web-shear cracking force of a region uncracked in bending, N: EN 1992-1-1 Eq. 6.4 with
    /// no axial stress and the mean tensile strength, V = I b / S · f_ctm = (2/3) b h f_ctm for
    /// a rectangle (the principal tension at the centroid reaches f_ctm).
    pub fn shear_cracking_force(&self) -> f64 {
        2.0 / 3.0 * self.width * self.height * self.tensile_strength
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 300 × 500 mm C30/37 section with 3 φ16 at 35 mm cover, worked by hand.
    fn worked_example() -> ConcreteSection {
        ConcreteSection::new(0.3, 0.5, &Reinforcement::default())
    }

    #[test]
    fn material_values_follow_table_3_1() {
        // Table 3.1 lists f_ctm = 2.9 MPa and E_cm = 33 GPa for C30/37.
        assert!((tensile_strength(30e6) / 1e6 - 2.9).abs() < 0.01);
        assert!((concrete_modulus(30e6) / 1e9 - 33.0).abs() < 0.2);
        // and 4.2 MPa, 37 GPa for C50/60; 4.6 MPa, 39 GPa for C70/85 (the logarithmic branch).
        assert!((tensile_strength(50e6) / 1e6 - 4.1).abs() < 0.05);
        assert!((tensile_strength(70e6) / 1e6 - 4.6).abs() < 0.05);
    }

    #[test]
    fn crack_width_matches_eq_7_8_by_hand() {
        let s = worked_example();
        // By hand: d = 0.5 − 0.035 − 0.008 = 0.457 m; A_s = 3π(0.016)²/4 = 6.0319e-4 m²;
        // f_ctm = 0.3·30^(2/3) = 2.8965 MPa; E_cm = 22·3.8^0.3 = 32.837 GPa; α_e = 6.0908;
        // x = 0.094257 m; I_II = b x³/3 + α_e A_s (d − x)² = 5.6716e-4 m⁴;
        // M_cr = f_ctm b h²/6 = 36.206 kN·m.
        assert!((s.effective_depth - 0.457).abs() < 1e-12);
        assert!((s.neutral_axis - 0.094257).abs() < 1e-6);
        assert!((s.cracked_inertia / 5.6716e-4 - 1.0).abs() < 1e-4);
        assert!((s.cracking_moment - 36_205.85).abs() < 0.1);
        // h_c,eff = min(2.5·0.043, (0.5 − 0.0943)/3, 0.25) = 0.1075 m; ρ_p,eff = 0.018703;
        // bars 107 mm apart ≤ 5(c + φ/2) = 215 mm, so Eq. 7.11:
        // s_r,max = 3.4·0.035 + 0.8·0.5·0.425·0.016/0.018703 = 0.26443 m.
        assert!((s.effective_ratio - 0.018703).abs() < 1e-6);
        assert!((s.crack_spacing - 0.264428).abs() < 1e-6);
        // At M = 80 kN·m: σ_s = α_e M (d − x)/I_II = 311.64 MPa;
        // ε_sm − ε_cm = (311.64 − 0.6·2.8965/0.018703·(1 + 6.0908·0.018703))/200000 = 1.04070e-3;
        // w_k = 0.26443 · 1.04070e-3 = 0.27519 mm.
        assert!((s.steel_stress(80e3) / 1e6 - 311.6426).abs() < 1e-3);
        assert!((s.crack_width(80e3) * 1e3 - 0.275190).abs() < 1e-5);
    }

    #[test]
    fn curvature_runs_from_uncracked_to_fully_cracked() {
        let s = worked_example();
        let e = s.concrete_modulus;
        let below = 0.9 * s.cracking_moment;
        assert!((s.curvature(below, e) * e * s.uncracked_inertia / below - 1.0).abs() < 1e-14);
        // Far above M_cr, ζ → 1: the fully cracked curvature.
        let far = 1e4 * s.cracking_moment;
        let ratio = s.curvature(far, e) / (far / (e * s.cracked_inertia));
        assert!((ratio - 1.0).abs() < 1e-6, "{ratio}");
        // Short-term (β = 1), just above M_cr, ζ ≈ 0: continuous.
        let above = 1.000001 * s.cracking_moment;
        assert!(
            (s.curvature(above, e) / s.curvature(below, e) / (1.000001 / 0.9) - 1.0).abs() < 1e-4
        );
        // Sign follows the moment.
        assert!(s.curvature(-2.0 * s.cracking_moment, e) < 0.0);
    }

    #[test]
    fn widely_spaced_bars_use_eq_7_14() {
        let bars = Reinforcement {
            bars: 2,
            ..Reinforcement::default()
        };
        let s = ConcreteSection::new(0.8, 0.5, &bars);
        // (0.8 − 0.07 − 0.016) = 0.714 m between the bars > 0.215 m.
        assert!((s.crack_spacing - 1.3 * (0.5 - s.neutral_axis)).abs() < 1e-12);
    }
}
