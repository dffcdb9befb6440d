//! `dataset.ground`: the ground under the structures, read from the recipe into a
//! [`GroundSpec`]. `ground: "grass"` is short for `ground: #{ material: "grass" }`.

use super::options::{OptResult, Options, number};
use crate::geometry::coordinate_in_range;
use crate::materials::ground::ground_material;
use crate::scene::GroundSpec;
use rhai::{Dynamic, Map};

/// The option a ground's height is read from.
const HEIGHT: &str = "dataset.ground.height";

/// The ground a recipe declares, if any. Its height must lie within the coordinate limit on
/// either side, as every vertex must: beyond it below, nothing else would refuse it.
pub fn ground(value: Option<Dynamic>) -> OptResult<Option<GroundSpec>> {
    let Some(value) = value else {
        return Ok(None);
    };
    if value.is_string() {
        let material =
            ground_material(&value.to_string()).map_err(|e| format!("dataset.ground: {e}"))?;
        return Ok(Some(GroundSpec {
            material,
            height: None,
            in_depth: false,
        }));
    }
    let map = value.try_cast::<Map>().ok_or(
        "dataset.ground must be a ground's name like \"grass\" or a map like #{ material: \"grass\", in_depth: false }",
    )?;
    let mut o = Options::new(map, "dataset.ground");
    let prompt = o.string("material", "grass")?;
    let material = ground_material(&prompt).map_err(|e| format!("dataset.ground.material: {e}"))?;
    let height = o
        .take("height")
        .map(|h| coordinate_in_range(number(&h, HEIGHT)?, HEIGHT))
        .transpose()?;
    let in_depth = o.flag("in_depth", false)?;
    o.finish()?;
    Ok(Some(GroundSpec {
        material,
        height,
        in_depth,
    }))
}
