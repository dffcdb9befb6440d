//! Damage on the members of a frame, placed by the recipe or by the frame's own mechanics, and
//! the frame analysed with the stiffness the damage leaves.
//!
//! Owns: the damaged analysis of a frame (`FrameModel::solve_damaged`) and its labels. The
//! damage records, the reinforced-concrete crack model and the placement rules are the beam
//! module's (`mechanics::damage`), read here along each member in its own frame (x from the
//! start node, z the section's height, sagging-positive moment about y). A damaged member keeps
//! a uniform share of its section's stiffness: the share with the same complementary bending
//! energy under its solved moment (docs/damage.md, "Frame members"), iterated with the frame's
//! solution until the shares settle, because a softer member sheds moment to its neighbours.

use super::{FrameModel, FrameSolution, SectionScale, SpaceSection};
use crate::mechanics::damage::{
    Cause, ConcreteSection, Damage, DamageRequest, DamageShape, InternalForces, crack_width_mm,
    exposed_corrosion, section_loss_regions, stress_cracks,
};
use crate::mechanics::{Section, damage::Face};
use glam::{DMat3, DVec3};
use serde::Serialize;

/// Largest change of any member's stiffness share between two passes at which the damaged
/// analysis stops.
pub const DAMAGE_TOLERANCE: f64 = 1e-10;
/// Most passes of the damaged analysis tried.
const DAMAGE_PASSES: usize = 200;
/// Gauss–Legendre pieces per stretch between breaks when the stiffness shares are integrated.
const PIECES: usize = 64;
/// A member is steep (a column, a post) when its axis is within 45° of the vertical: its
/// underside is a side in the world, where water does not collect.
const STEEP: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// What the damage of a frame is and what it did to the frame.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FrameDamage {
    /// Every damage of the frame, member by member in the order of `members` (placed, then by
    /// stress, then by exposure); `member` names the model's member (`members[i]`). The damage
    /// layers' instance ids are index + 1 here.
    pub items: Vec<Damage>,
    /// Each damaged member: what its damage left of its stiffness.
    pub members: Vec<MemberDamage>,
    /// Whether the damage changed any member's stiffness, so the frame was solved (and meshed)
    /// with the damaged stiffness.
    pub stiffness_changed: bool,
    /// Passes of the damaged analysis until the members' stiffness shares settled (0 when the
    /// stiffness did not change).
    pub passes: usize,
    /// The sound frame's largest translation of any point of the members' axes, metres.
    pub sound_max_displacement: f64,
}

/// A damaged member of a frame.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct MemberDamage {
    /// Index of the member in `model.members`.
    pub member: usize,
    /// Its items: `items[first_item .. first_item + item_count]` of the frame's damage.
    pub first_item: usize,
    /// How many items it has.
    pub item_count: usize,
    /// For reinforced concrete, the section the crack model solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub concrete: Option<ConcreteSection>,
    /// The uniform share of A, I_y and I_z (with J) the member was analysed with.
    pub section_scale: SectionScale,
    /// Widest crack, millimetres (0 without cracks).
    pub max_crack_width_mm: f64,
}

/// A damaged member as its damage model sees it: what was placed and what its section does.
struct MemberPlan {
    member: usize,
    /// Placed and exposure items (cracks by stress come after the analysis).
    items: Vec<Damage>,
    concrete: Option<ConcreteSection>,
    /// (from, to, share of the section remaining) of each region with section loss.
    regions: Vec<(f64, f64, f64)>,
}

impl MemberPlan {
    fn changes_stiffness(&self) -> bool {
        self.concrete.is_some() || !self.regions.is_empty()
    }

    /// Share of the section remaining at x (overlapping regions multiply).
    fn remaining(&self, x: f64) -> f64 {
        self.regions
            .iter()
            .filter(|(from, to, _)| (*from..*to).contains(&x))
            .map(|r| r.2)
            .product()
    }
}

/// The strong-axis internal forces of member `m` of a solution, for the crack rules.
struct MemberForces<'a> {
    solution: &'a FrameSolution,
    m: usize,
    length: f64,
}

impl InternalForces for MemberForces<'_> {
    fn moment(&self, x: f64) -> f64 {
        self.solution.strong_axis_at(self.m, x).moment
    }

    /// V = dM/dx by central differences (one-sided at the ends).
    fn shear(&self, x: f64) -> f64 {
        let h = 1e-6 * self.length;
        let (a, b) = ((x - h).max(0.0), (x + h).min(self.length));
        (self.moment(b) - self.moment(a)) / (b - a)
    }
}

impl FrameModel {
    /// Rows: member `m`'s local x, y, z axes in world coordinates (as the analysis takes them).
    pub fn member_axes(&self, m: usize) -> DMat3 {
        let member = &self.members[m];
        super::element::local_axes(
            DVec3::from_array(self.nodes[member.start]),
            DVec3::from_array(self.nodes[member.end]),
            member.roll,
        )
    }

    /// Linear static analysis with the damage the model asks for: placed damage as given,
    /// reinforced-concrete members cracked where their solved moment and shear exceed the
    /// concrete's resistance, steel members corroded by exposure, and every member whose
    /// damage lowers its stiffness analysed with it. Without damage: `solve`, unchanged.
    pub fn solve_damaged(&self) -> Result<(FrameSolution, Option<FrameDamage>), String> {
        if self.damage.is_empty() {
            return Ok((self.solve()?, None));
        }
        self.validate()?;
        if !self.vibration.is_empty() {
            return Err("damage on a frame needs a static analysis; this frame draws a vibration snapshot (vibration modes are of the sound frame)".into());
        }
        let plans = self.damage_plans()?;
        let sound = self.solve()?;
        let sound_max_displacement = super::FrameLabels::new(&sound).max_displacement;
        let (solution, scales, passes) = match plans.iter().any(MemberPlan::changes_stiffness) {
            true => self.settle(&plans, &sound)?,
            false => (sound, vec![SectionScale::ONE; plans.len()], 0),
        };
        let mut items = Vec::new();
        let mut members = Vec::new();
        for (plan, scale) in plans.into_iter().zip(scales) {
            let mut own = plan.items;
            if let Some(c) = &plan.concrete {
                let forces = MemberForces {
                    solution: &solution,
                    m: plan.member,
                    length: solution.member_length(plan.member),
                };
                own.extend(stress_cracks(
                    &member_name(plan.member),
                    forces.length,
                    c,
                    &forces,
                ));
            }
            members.push(MemberDamage {
                member: plan.member,
                first_item: items.len(),
                item_count: own.len(),
                concrete: plan.concrete,
                section_scale: scale,
                max_crack_width_mm: own.iter().map(crack_width_mm).fold(0.0, f64::max),
            });
            items.extend(own);
        }
        let damage = FrameDamage {
            items,
            stiffness_changed: members.iter().any(|m| m.section_scale != SectionScale::ONE),
            members,
            passes,
            sound_max_displacement,
        };
        Ok((solution, Some(damage)))
    }

    /// The damage model of every member the model asks damage for.
    fn damage_plans(&self) -> Result<Vec<MemberPlan>, String> {
        self.damage
            .iter()
            .map(|(&m, request)| {
                let member = self.members.get(m).ok_or_else(|| {
                    format!(
                        "damage asked for member {m}, but the frame has {} members",
                        self.members.len()
                    )
                })?;
                self.member_plan(m, &member.section, request)
                    .map_err(|e| format!("member {m}: {e}"))
            })
            .collect()
    }

    fn member_plan(
        &self,
        m: usize,
        section: &Section,
        request: &DamageRequest,
    ) -> Result<MemberPlan, String> {
        let concrete = match (&request.reinforcement, section) {
            (None, _) => None,
            (Some(r), Section::Rectangle { width, height }) => {
                r.validate(*height)?;
                Some(ConcreteSection::new(*width, *height, r))
            }
            (Some(_), other) => {
                return Err(format!(
                    "reinforced concrete needs a rectangular section (got {other:?})"
                ));
            }
        };
        let mut items = request.placed.clone();
        if let Some(rules) = &request.corrosion_by_exposure {
            items.extend(self.exposure_items(m, rules));
        }
        for d in &mut items {
            d.member = member_name(m);
        }
        let regions = section_loss_regions(&items);
        Ok(MemberPlan {
            member: m,
            items,
            concrete,
            regions,
        })
    }

    /// Corrosion by exposure on member `m`: its ends at joints (where another member meets it)
    /// and at supports (base plates, bearings), and, on a member that is not steep, its
    /// underside. A steep member's end regions wrap all four faces (water runs down it and
    /// stands on its base plate).
    fn exposure_items(
        &self,
        m: usize,
        rules: &crate::mechanics::damage::ExposureRules,
    ) -> Vec<Damage> {
        let member = &self.members[m];
        let length = DVec3::from_array(self.nodes[member.start])
            .distance(DVec3::from_array(self.nodes[member.end]));
        let wet = |node: usize| {
            self.supports.iter().any(|s| s.node == node)
                || self
                    .members
                    .iter()
                    .enumerate()
                    .any(|(k, o)| k != m && (o.start == node || o.end == node))
        };
        let ends: Vec<f64> = [(member.start, 0.0), (member.end, length)]
            .into_iter()
            .filter(|(node, _)| wet(*node))
            .map(|(_, x)| x)
            .collect();
        let mut items = exposed_corrosion(length, &member.section, &ends, rules);
        let axes = self.member_axes(m);
        let steep = axes.row(0).z.abs() > STEEP;
        // Down (world −Z) in the member's own frame: where the stains run.
        let down = axes * DVec3::NEG_Z;
        items.retain_mut(|d| {
            let underside = matches!(&d.cause, Cause::Exposure { rule } if rule == "bottom_flange");
            let DamageShape::Corrosion {
                faces,
                stain_direction,
                ..
            } = &mut d.shape
            else {
                return true;
            };
            *stain_direction = down.to_array();
            if steep && !underside {
                faces.push(Face::Top);
            }
            !(steep && underside)
        });
        items
    }

    /// Iterates the analysis with each damaged member's stiffness shares from the previous
    /// pass's moments until no share changes by more than [`DAMAGE_TOLERANCE`].
    fn settle(
        &self,
        plans: &[MemberPlan],
        sound: &FrameSolution,
    ) -> Result<(FrameSolution, Vec<SectionScale>, usize), String> {
        let mut scales = vec![SectionScale::ONE; plans.len()];
        let mut solution = sound.clone();
        for pass in 1..=DAMAGE_PASSES {
            let next: Vec<SectionScale> = plans
                .iter()
                .map(|p| self.stiffness_share(p, &solution))
                .collect();
            let change = scales
                .iter()
                .zip(&next)
                .map(|(a, b)| {
                    (a.area - b.area)
                        .abs()
                        .max((a.strong - b.strong).abs())
                        .max((a.weak - b.weak).abs())
                })
                .fold(0.0, f64::max);
            scales = next;
            let mut damaged = self.clone();
            damaged.damage.clear();
            for (p, s) in plans.iter().zip(&scales) {
                damaged.members[p.member].section_scale = *s;
            }
            solution = damaged.solve()?;
            if change <= DAMAGE_TOLERANCE {
                return Ok((solution, scales, pass));
            }
        }
        Err(format!(
            "the damaged frame did not settle in {DAMAGE_PASSES} passes: its cracked members keep shedding moment"
        ))
    }

    /// The uniform shares of a damaged member's stiffness. Bending about y: the share with
    /// the member's complementary bending energy under the moment M(x) of `solution`,
    /// ∫ M²/(E I_y) dx / ∫ M κ(x, M) dx, κ the damaged curvature (cracked concrete by
    /// EN 1992-1-1 Eq. 7.18, section loss by 1/(1 − α)). Where M vanishes, and for A, I_z and
    /// J: the length-weighted harmonic mean of the section remaining (exact for a constant
    /// force along the member).
    fn stiffness_share(&self, plan: &MemberPlan, solution: &FrameSolution) -> SectionScale {
        let m = plan.member;
        let member = &self.members[m];
        let length = solution.member_length(m);
        let e = member.elastic_modulus * member.stiffness_factor;
        let i = SpaceSection::of(&member.section, member.poisson).i_y;
        let mut breaks: Vec<f64> = vec![0.0, length];
        breaks.extend(plan.regions.iter().flat_map(|r| [r.0, r.1]));
        breaks.extend(solution.member_kinks(m));
        let harmonic = match plan.regions.is_empty() {
            true => 1.0,
            false => length / integrate(&breaks, length, &|x| 1.0 / plan.remaining(x)),
        };
        let curvature = |x: f64, moment: f64| match &plan.concrete {
            Some(c) => c.curvature(moment, e) / plan.remaining(x),
            None => moment / (e * i * plan.remaining(x)),
        };
        let moment = |x: f64| solution.strong_axis_at(m, x).moment;
        let sound = integrate(&breaks, length, &|x| moment(x).powi(2) / (e * i));
        let damaged = integrate(&breaks, length, &|x| {
            let mx = moment(x);
            mx * curvature(x, mx)
        });
        let strong = if sound > 0.0 && damaged > 0.0 {
            sound / damaged
        } else {
            harmonic
        };
        SectionScale {
            area: harmonic,
            strong,
            weak: harmonic,
        }
    }
}

/// The name a frame member's damage records carry: the model's member it is on.
fn member_name(m: usize) -> String {
    format!("members[{m}]")
}

/// ∫₀ᴸ f by three-point Gauss–Legendre on `PIECES` pieces of every stretch between `breaks`
/// (so a jump of f at a break is integrated exactly, and f polynomial of degree ≤ 5 between
/// breaks too).
fn integrate(breaks: &[f64], length: f64, f: &dyn Fn(f64) -> f64) -> f64 {
    let mut at: Vec<f64> = breaks.iter().map(|b| b.clamp(0.0, length)).collect();
    at.sort_by(f64::total_cmp);
    at.dedup();
    let nodes = [-(0.6f64).sqrt(), 0.0, (0.6f64).sqrt()];
    let weights = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let mut sum = 0.0;
    for w in at.windows(2) {
        let h = (w[1] - w[0]) / PIECES as f64;
        for k in 0..PIECES {
            let mid = w[0] + (k as f64 + 0.5) * h;
            for (t, c) in nodes.iter().zip(&weights) {
                sum += 0.5 * h * c * f(mid + 0.5 * h * t);
            }
        }
    }
    sum
}
