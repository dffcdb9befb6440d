//! Ground materials: the prompt of a ground ("grass", "gravel", "asphalt", "concrete slab",
//! "soil", "water") compiled into a material of the existing bases, with the colour of the
//! real surface seen from a few metres up.
//!
//! Owns: the ground vocabulary and each ground's look. Must not touch: the structure prompt
//! vocabulary (a ground word is not a structure material) or the generators, which it reuses:
//! `Base::Ground`'s mottle for grass, asphalt, slab and soil (at twice its size on grass and
//! soil, half on asphalt; a structure's concrete would add formwork joints and tie holes),
//! rubble stone at 0.15 of its size for gravel. No conditions are layered on: the ground
//! covers most of an outdoor image, and every layer costs per pixel.
//!
//! Colours are sRGB chosen so that the linear albedo falls within the broadband albedos
//! measured for each surface (Oke, *Boundary Layer Climates*, 2nd ed. 1987, table 1.1): grass
//! 0.16–0.26, gravel about 0.2–0.3 (taken as light rock), asphalt 0.05–0.20, concrete
//! 0.10–0.35, dry soil 0.17–0.30 (dark, wet soil down to 0.05), water 0.03–0.10 at high sun.

use super::{Base, Material, Texture};

/// The grounds a recipe can ask for, with the words that name them.
const GROUNDS: [(&str, &[&str]); 6] = [
    ("grass", &["grass", "lawn", "meadow"]),
    ("gravel", &["gravel", "ballast", "shingle"]),
    ("asphalt", &["asphalt", "tarmac", "road"]),
    (
        "concrete slab",
        &["concrete slab", "concrete", "slab", "pavement"],
    ),
    ("soil", &["soil", "earth", "dirt", "mud"]),
    ("water", &["water", "river", "lake"]),
];

/// The ground names, one per kind, for messages and docs.
pub fn ground_names() -> Vec<&'static str> {
    GROUNDS.iter().map(|(name, _)| *name).collect()
}

/// The material of the ground named by `prompt` (case and surrounding spaces ignored); an
/// unknown name is an error naming the nearest known one.
pub fn ground_material(prompt: &str) -> Result<Material, String> {
    let words = prompt.trim().to_lowercase();
    let Some((name, _)) = GROUNDS
        .iter()
        .find(|(_, names)| names.contains(&words.as_str()))
    else {
        let every: Vec<&str> = GROUNDS
            .iter()
            .flat_map(|(_, n)| n.iter().copied())
            .collect();
        let hint = crate::words::nearest(&words, &every)
            .map(|k| format!("; did you mean \"{k}\"?"))
            .unwrap_or_default();
        return Err(format!(
            "unknown ground \"{prompt}\"{hint} (known: {})",
            ground_names().join(", ")
        ));
    };
    let (base, colour, roughness, specular, scale, conditions) = match *name {
        "grass" => (Base::Ground, [0.46, 0.57, 0.28], 1.0, 0.02, 2.0, vec![]),
        "gravel" => (Base::Stone, [0.58, 0.56, 0.52], 1.0, 0.03, 0.15, vec![]),
        "asphalt" => (Base::Ground, [0.33, 0.33, 0.34], 0.9, 0.04, 0.5, vec![]),
        "concrete slab" => (Base::Ground, [0.62, 0.61, 0.58], 0.9, 0.04, 1.0, vec![]),
        "soil" => (Base::Ground, [0.48, 0.4, 0.31], 1.0, 0.02, 2.0, vec![]),
        _ => (Base::Plain, [0.24, 0.3, 0.32], 0.1, 0.02, 1.0, vec![]),
    };
    Ok(Material {
        prompt: Some(name.to_string()),
        base,
        colour,
        roughness,
        specular,
        conditions,
        scale,
        texture: Texture::Procedural,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::srgb_to_linear;

    /// Linear broadband albedo (the mean of the channels) within the measured range of each
    /// surface (Oke 1987, table 1.1).
    #[test]
    fn ground_albedos_fall_within_measured_ranges() {
        let measured = [
            ("grass", 0.16, 0.26),
            ("gravel", 0.2, 0.3),
            ("asphalt", 0.05, 0.2),
            ("concrete slab", 0.1, 0.35),
            ("soil", 0.05, 0.3),
            ("water", 0.03, 0.1),
        ];
        for (name, lo, hi) in measured {
            let m = ground_material(name).unwrap();
            let albedo = m.colour.map(srgb_to_linear).iter().sum::<f64>() / 3.0;
            assert!((lo..=hi).contains(&albedo), "{name}: {albedo}");
        }
    }

    #[test]
    fn synonyms_and_case_name_one_ground_and_typos_get_a_suggestion() {
        assert_eq!(
            ground_material(" Tarmac ").unwrap().prompt.as_deref(),
            Some("asphalt")
        );
        let err = ground_material("grasss").unwrap_err();
        assert!(err.contains("did you mean \"grass\""), "{err}");
        assert!(ground_material("lava").is_err());
    }
}
