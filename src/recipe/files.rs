//! Files a recipe names: mesh files, texture images and background folders. All are read
//! only from inside the recipe's folder, once per recipe, and hashed into the dataset's
//! identity (a changed texture is a different dataset).

use super::engine::Sources;
use crate::geometry::Mesh;
use crate::geometry::import::{ImportOptions, import_mesh};
use crate::materials::image::{ImageFile, TextureImage};
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Image files a texture or background may be.
pub const IMAGE_EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

pub struct RecipeFiles {
    folder: PathBuf,
    sources: Arc<Sources>,
    meshes: Mutex<BTreeMap<(String, bool), Arc<Mesh>>>,
    images: Mutex<BTreeMap<String, ImageFile>>,
}

impl RecipeFiles {
    pub fn new(folder: &Path, sources: Arc<Sources>) -> Self {
        RecipeFiles {
            folder: folder.to_path_buf(),
            sources,
            meshes: Mutex::default(),
            images: Mutex::default(),
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

    /// Reads a file and records its hash in the recipe's identity.
    fn read(&self, path: &Path, kind: &str) -> Result<Vec<u8>, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        self.sources.insert(
            &path.display().to_string(),
            &format!("{kind} file, blake3 {}", blake3::hash(&bytes).to_hex()),
        );
        Ok(bytes)
    }

    pub fn mesh(&self, file: &str, normalize: bool) -> Result<Arc<Mesh>, String> {
        let key = (file.to_string(), normalize);
        if let Some(mesh) = self.meshes.lock().unwrap().get(&key) {
            return Ok(mesh.clone());
        }
        let path = self.inside(file, "shape::mesh")?;
        let imported = import_mesh(&path, ImportOptions { normalize })?;
        for warning in &imported.warnings {
            eprintln!("warning: {}: {warning}", path.display());
        }
        self.read(&path, "mesh")?;
        let mesh = Arc::new(imported.mesh);
        self.meshes.lock().unwrap().insert(key, mesh.clone());
        Ok(mesh)
    }

    /// A texture or background image named by the recipe; `what` names the call for errors.
    pub fn image(&self, file: &str, what: &str) -> Result<ImageFile, String> {
        if let Some(image) = self.images.lock().unwrap().get(file) {
            return Ok(image.clone());
        }
        let path = self.inside(file, what)?;
        if !path.is_file() {
            return Err(format!(
                "{what}: image file \"{file}\" not found (looked for {})",
                path.display()
            ));
        }
        let bytes = self.read(&path, "image")?;
        let image = ImageFile {
            name: file.to_string(),
            hash: blake3::hash(&bytes).to_hex().to_string(),
            image: Arc::new(TextureImage::decode(&bytes, &path)?),
        };
        self.images
            .lock()
            .unwrap()
            .insert(file.to_string(), image.clone());
        Ok(image)
    }

    /// The image `folder/stem.{png,jpg,jpeg}`, if one exists.
    pub fn image_named(&self, folder: &str, stem: &str) -> Result<Option<ImageFile>, String> {
        for ext in IMAGE_EXTENSIONS {
            let file = format!("{folder}/{stem}.{ext}");
            if self.inside(&file, "texture")?.is_file() {
                return self.image(&file, "texture").map(Some);
            }
        }
        Ok(None)
    }

    /// Every image in `folder`, in name order.
    pub fn images_in(&self, folder: &str, what: &str) -> Result<Vec<ImageFile>, String> {
        let path = self.inside(folder, what)?;
        let entries = std::fs::read_dir(&path)
            .map_err(|e| format!("{what} = \"{folder}\": {}: {e}", path.display()))?;
        let mut names: Vec<String> = entries
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| {
                Path::new(n).extension().is_some_and(|x| {
                    IMAGE_EXTENSIONS.contains(&x.to_string_lossy().to_lowercase().as_str())
                })
            })
            .collect();
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
