//! Files a recipe names: mesh files, texture images and background folders. All are read
//! only from inside the recipe's folder (by their real paths, see `access`), once per recipe,
//! within size bounds, and hashed into the dataset's identity (a changed texture is a
//! different dataset).

use super::access::{Allowed, Kind};
use super::engine::Sources;
use super::memory;
use crate::geometry::Mesh;
use crate::geometry::import::{ImportOptions, import_mesh};
use crate::materials::environment::EnvironmentMap;
use crate::materials::image::{ImageFile, TextureImage};
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Image files a texture or background may be.
pub const IMAGE_EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

/// Most images a background folder may hold.
pub const MAX_FOLDER_IMAGES: usize = 10_000;
/// Most pixels all of a recipe's decoded images may hold together (textures and backgrounds;
/// each pixel takes 16 bytes once decoded, its mip levels included).
pub const MAX_TOTAL_PIXELS: u64 = 1 << 28;

pub struct RecipeFiles {
    folder: PathBuf,
    allowed: Allowed,
    sources: Arc<Sources>,
    meshes: Mutex<BTreeMap<(String, bool), Arc<Mesh>>>,
    images: Mutex<BTreeMap<String, ImageFile>>,
    /// Environment maps by file, with their hashes: read and projected once per recipe.
    environments: Mutex<BTreeMap<String, (String, Arc<EnvironmentMap>)>>,
    pixels: Mutex<u64>,
}

impl RecipeFiles {
    pub fn new(folder: &Path, sources: Arc<Sources>) -> Self {
        RecipeFiles {
            folder: folder.to_path_buf(),
            allowed: Allowed::new(folder),
            sources,
            meshes: Mutex::default(),
            images: Mutex::default(),
            environments: Mutex::default(),
            pixels: Mutex::default(),
        }
    }

    /// The recipe-folder path of `file`, refusing anything that could leave the folder.
    fn inside(&self, file: &str, what: &str) -> Result<PathBuf, String> {
        let relative = Path::new(file);
        if file.is_empty()
            || !relative
                .components()
                .all(|c| matches!(c, Component::Normal(_)))
        {
            return Err(format!(
                "{what} \"{file}\": files are named relative to the recipe's folder, without '..' or absolute paths"
            ));
        }
        Ok(self.folder.join(relative))
    }

    /// Reads an allowed file (see `access`) and records its hash in the recipe's identity;
    /// None when there is no such file. `what` names the call for errors.
    fn read(&self, path: &Path, kind: Kind, what: &str) -> Result<Option<Vec<u8>>, String> {
        let Some(bytes) = self
            .allowed
            .read(path, kind)
            .map_err(|e| format!("{what}: {e}"))?
        else {
            return Ok(None);
        };
        self.sources.insert(
            &path.display().to_string(),
            &format!(
                "{} file, blake3 {}",
                kind.noun(),
                blake3::hash(&bytes).to_hex()
            ),
        );
        Ok(Some(bytes))
    }

    pub fn mesh(&self, file: &str, normalize: bool) -> Result<Arc<Mesh>, String> {
        let key = (file.to_string(), normalize);
        if let Some(mesh) = self.meshes.lock().unwrap().get(&key) {
            return Ok(mesh.clone());
        }
        let path = self.inside(file, "shape::mesh")?;
        // A missing file is left to the importer, which says so in its own words.
        if let Some(bytes) = memory::exempt(|| self.read(&path, Kind::Mesh, "shape::mesh"))? {
            self.check_gltf_buffers(&path, &bytes)?;
        }
        let imported = memory::exempt(|| import_mesh(&path, ImportOptions { normalize }))?;
        for warning in &imported.warnings {
            eprintln!("warning: {}: {warning}", path.display());
        }
        let mesh = Arc::new(imported.mesh);
        self.meshes.lock().unwrap().insert(key, mesh.clone());
        Ok(mesh)
    }

    /// A glTF's buffer files are read by the importer from next to it: they obey the same
    /// rules as the mesh file (inside the allowed folders, regular, bounded).
    fn check_gltf_buffers(&self, path: &Path, bytes: &[u8]) -> Result<(), String> {
        let is_gltf = path.extension().is_some_and(|e| {
            let e = e.to_string_lossy().to_lowercase();
            e == "gltf" || e == "glb"
        });
        // A file that does not parse is the importer's to report.
        let Some(gltf) = is_gltf
            .then(|| gltf::Gltf::from_slice_without_validation(bytes).ok())
            .flatten()
        else {
            return Ok(());
        };
        let dir = path.parent().unwrap_or(Path::new("."));
        for buffer in gltf.buffers() {
            if let gltf::buffer::Source::Uri(uri) = buffer.source() {
                if uri.starts_with("data:") {
                    continue;
                }
                let file = dir.join(uri);
                self.allowed.check(&file, Kind::Mesh).map_err(|e| {
                    format!(
                        "shape::mesh: {}: buffer {}: {e}",
                        path.display(),
                        buffer.index()
                    )
                })?;
            }
        }
        Ok(())
    }

    /// A texture or background image named by the recipe; `what` names the call for errors.
    pub fn image(&self, file: &str, what: &str) -> Result<ImageFile, String> {
        if let Some(image) = self.images.lock().unwrap().get(file) {
            return Ok(image.clone());
        }
        let path = self.inside(file, what)?;
        let (hash, image) = memory::exempt(|| -> Result<_, String> {
            let bytes = self.read(&path, Kind::Image, what)?.ok_or_else(|| {
                format!(
                    "{what}: image file \"{file}\" not found (looked for {})",
                    path.display()
                )
            })?;
            let (width, height) = TextureImage::size(&bytes, &path)?;
            self.count_pixels(u64::from(width) * u64::from(height), &path)?;
            let image = TextureImage::decode(&bytes, &path)?;
            Ok((blake3::hash(&bytes).to_hex().to_string(), image))
        })?;
        let image = ImageFile {
            name: file.to_string(),
            hash,
            image: Arc::new(image),
        };
        self.images
            .lock()
            .unwrap()
            .insert(file.to_string(), image.clone());
        Ok(image)
    }

    /// An environment map (Radiance .hdr) named by the recipe, with the blake3 hash of its
    /// bytes; decoded and projected onto SH once however often it is named. `what` names the
    /// option for errors.
    pub fn environment(
        &self,
        file: &str,
        what: &str,
    ) -> Result<(String, Arc<EnvironmentMap>), String> {
        if let Some(found) = self.environments.lock().unwrap().get(file) {
            return Ok(found.clone());
        }
        let path = self.inside(file, what)?;
        let found = memory::exempt(|| -> Result<_, String> {
            let bytes = self.read(&path, Kind::Image, what)?.ok_or_else(|| {
                format!(
                    "{what}: environment map \"{file}\" not found (looked for {})",
                    path.display()
                )
            })?;
            let (width, height) =
                EnvironmentMap::size(&bytes, &path).map_err(|e| format!("{what}: {e}"))?;
            self.count_pixels(u64::from(width) * u64::from(height), &path)?;
            let map = EnvironmentMap::decode(&bytes, &path).map_err(|e| format!("{what}: {e}"))?;
            Ok((blake3::hash(&bytes).to_hex().to_string(), Arc::new(map)))
        })?;
        self.environments
            .lock()
            .unwrap()
            .insert(file.to_string(), found.clone());
        Ok(found)
    }

    /// Adds an image about to be decoded to the recipe's total, failing past
    /// `MAX_TOTAL_PIXELS`.
    fn count_pixels(&self, pixels: u64, path: &Path) -> Result<(), String> {
        let mut total = self.pixels.lock().unwrap();
        *total += pixels;
        if *total > MAX_TOTAL_PIXELS {
            return Err(format!(
                "{}: the recipe's images hold more than {} million pixels together, the limit for the images of one recipe",
                path.display(),
                MAX_TOTAL_PIXELS / 1_000_000
            ));
        }
        Ok(())
    }

    /// The image `folder/stem.{png,jpg,jpeg}`, if one exists. Something there that is not an
    /// allowed image file (a link leaving the folder, a fifo) is an error, not ignored.
    pub fn image_named(&self, folder: &str, stem: &str) -> Result<Option<ImageFile>, String> {
        for ext in IMAGE_EXTENSIONS {
            let file = format!("{folder}/{stem}.{ext}");
            if std::fs::symlink_metadata(self.inside(&file, "texture")?).is_ok() {
                return self.image(&file, "texture").map(Some);
            }
        }
        Ok(None)
    }

    /// Every image in `folder`, in name order.
    pub fn images_in(&self, folder: &str, what: &str) -> Result<Vec<ImageFile>, String> {
        let path = self.inside(folder, what)?;
        let real = self
            .allowed
            .resolve(&path)
            .map_err(|e| format!("{what} = \"{folder}\": {e}"))?
            .ok_or_else(|| format!("{what} = \"{folder}\": {}: no such folder", path.display()))?;
        let entries = std::fs::read_dir(&real)
            .map_err(|e| format!("{what} = \"{folder}\": {}: {e}", path.display()))?;
        let mut names: Vec<String> = entries
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| {
                Path::new(n).extension().is_some_and(|x| {
                    IMAGE_EXTENSIONS.contains(&x.to_string_lossy().to_lowercase().as_str())
                })
            })
            .take(MAX_FOLDER_IMAGES + 1)
            .collect();
        if names.len() > MAX_FOLDER_IMAGES {
            return Err(format!(
                "{what} = \"{folder}\": more than {MAX_FOLDER_IMAGES} images in {}",
                path.display()
            ));
        }
        names.sort();
        if names.is_empty() {
            return Err(format!(
                "{what} = \"{folder}\": no PNG or JPEG images in {}",
                path.display()
            ));
        }
        names
            .iter()
            .map(|n| self.image(&format!("{folder}/{n}"), what))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_images_of_a_recipe_share_one_pixel_budget() {
        let files = RecipeFiles::new(Path::new("."), Arc::default());
        let path = Path::new("bg/a.png");
        files.count_pixels(MAX_TOTAL_PIXELS - 1, path).unwrap();
        files.count_pixels(1, path).unwrap();
        let e = files.count_pixels(1, path).unwrap_err();
        assert!(e.contains("more than 268 million pixels together"), "{e}");
    }
}
