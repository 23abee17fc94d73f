//! The page's files, embedded in the binary: no network and no file system at run time.
//!
//! three.js 0.187.0 (MIT, its LICENSE served beside it) is vendored unchanged from the npm
//! package under `assets/vendor/three/` (see the README there); OrbitControls' bare
//! `'three'` import is pointed at `./three.module.js` here, so the page needs no import map.

use std::sync::OnceLock;

/// One embedded file.
#[derive(Clone, Copy, Debug)]
pub struct Asset {
    /// Its Content-Type.
    pub content_type: &'static str,
    /// Its bytes.
    pub bytes: &'static [u8],
}

const JS: &str = "text/javascript; charset=utf-8";

static ORBIT: OnceLock<String> = OnceLock::new();

fn orbit_controls() -> &'static [u8] {
    ORBIT
        .get_or_init(|| {
            include_str!("assets/vendor/three/OrbitControls.js")
                .replace("} from 'three';", "} from './three.module.js';")
        })
        .as_bytes()
}

/// The embedded file served at `path` (an exact match; nothing else is served from here).
pub fn find(path: &str) -> Option<Asset> {
    let (content_type, bytes): (&'static str, &'static [u8]) = match path {
        "/" | "/index.html" => ("text/html; charset=utf-8", include_bytes!("assets/index.html")),
        "/assets/app.js" => (JS, include_bytes!("assets/app.js")),
        "/assets/brdf.js" => (JS, include_bytes!("assets/brdf.js")),
        "/assets/lic.js" => (JS, include_bytes!("assets/lic.js")),
        "/assets/style.css" => ("text/css; charset=utf-8", include_bytes!("assets/style.css")),
        "/assets/three.module.js" => (JS, include_bytes!("assets/vendor/three/three.module.js")),
        "/assets/three.core.js" => (JS, include_bytes!("assets/vendor/three/three.core.js")),
        "/assets/OrbitControls.js" => (JS, orbit_controls()),
        "/assets/three-LICENSE.txt" => {
            ("text/plain; charset=utf-8", include_bytes!("assets/vendor/three/LICENSE"))
        }
        _ => return None,
    };
    Some(Asset { content_type, bytes })
}

/// Every asset path.
pub const ALL: &[&str] = &[
    "/",
    "/assets/app.js",
    "/assets/brdf.js",
    "/assets/lic.js",
    "/assets/style.css",
    "/assets/three.module.js",
    "/assets/three.core.js",
    "/assets/OrbitControls.js",
    "/assets/three-LICENSE.txt",
];
