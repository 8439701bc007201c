//! The `drivers` step of `cargo xtask test`: what the backends, the renderer's tests and the
//! viewer load at run time, checked by file; installed with apt-get as root.

use crate::test::Outcome;
use std::path::Path;
use std::process::Command;

/// The apt packages that provide the drivers the backends load at run time.
const APT_PACKAGES: &[&str] = &[
    "mesa-vulkan-drivers",
    "libvulkan1",
    "pocl-opencl-icd",
    "ocl-icd-libopencl1",
    "glslang-tools",
    "vulkan-validationlayers",
    "xvfb",
    "libx11-6",
    "libx11-xcb1",
    "libxcursor1",
    "libxrandr2",
    "libxi6",
    "libxkbcommon-x11-0",
    "libegl1",
    "libegl-mesa0",
    "libgl1-mesa-dri",
];

/// One driver requirement: a name and whether it is present.
struct Requirement {
    what: &'static str,
    present: bool,
}

fn any_file(dirs: &[&str], pred: &dyn Fn(&str) -> bool) -> bool {
    dirs.iter().any(|d| {
        std::fs::read_dir(d).is_ok_and(|entries| {
            entries
                .flatten()
                .any(|e| e.file_name().to_str().is_some_and(pred))
        })
    })
}

/// Folders where shared libraries live on Debian-like and other Linux systems.
fn lib_dirs() -> Vec<String> {
    let mut dirs: Vec<String> = ["/usr/lib", "/usr/lib64", "/lib", "/lib64", "/usr/local/lib"]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    for base in ["/usr/lib", "/lib"] {
        if let Ok(entries) = std::fs::read_dir(base) {
            for e in entries.flatten() {
                let name = e.file_name();
                if name.to_str().is_some_and(|n| n.ends_with("-linux-gnu")) {
                    dirs.push(e.path().display().to_string());
                }
            }
        }
    }
    dirs
}

fn in_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(program).is_file()))
}

fn requirements() -> Vec<Requirement> {
    let libs = lib_dirs();
    let libs: Vec<&str> = libs.iter().map(String::as_str).collect();
    vec![
        Requirement {
            what: "Vulkan loader (libvulkan.so.1)",
            present: any_file(&libs, &|n| n.starts_with("libvulkan.so")),
        },
        Requirement {
            what: "Mesa lavapipe Vulkan ICD (/usr/share/vulkan/icd.d/lvp_icd*.json)",
            present: any_file(&["/usr/share/vulkan/icd.d"], &|n| {
                n.starts_with("lvp_icd") && n.ends_with(".json")
            }),
        },
        Requirement {
            what: "OpenCL ICD loader (libOpenCL.so.1)",
            present: any_file(&libs, &|n| n.starts_with("libOpenCL.so")),
        },
        Requirement {
            what: "PoCL OpenCL platform (/etc/OpenCL/vendors/pocl.icd)",
            present: Path::new("/etc/OpenCL/vendors/pocl.icd").is_file(),
        },
        Requirement {
            what: "OpenGL through Mesa's EGL and llvmpipe (libEGL_mesa.so.0, the renderer's \
                   OpenGL test)",
            present: any_file(&libs, &|n| n.starts_with("libEGL_mesa.so")),
        },
        Requirement {
            what: "glslangValidator",
            present: in_path("glslangValidator"),
        },
        Requirement {
            what: "Xvfb (a virtual X server for the viewer's window test)",
            present: in_path("Xvfb"),
        },
        Requirement {
            what: "X11 client libraries (libX11, libXcursor, libXrandr, libXi, libxkbcommon-x11)",
            present: [
                "libX11.so",
                "libXcursor.so",
                "libXrandr.so",
                "libXi.so",
                "libxkbcommon-x11.so",
            ]
            .iter()
            .all(|lib| any_file(&libs, &|n| n.starts_with(lib))),
        },
        Requirement {
            what: "Vulkan validation layer (VK_LAYER_KHRONOS_validation)",
            present: any_file(&["/usr/share/vulkan/explicit_layer.d"], &|n| {
                n.eq_ignore_ascii_case("VkLayer_khronos_validation.json")
            }),
        },
    ]
}

/// Whether the Vulkan loader and lavapipe are installed.
pub(crate) fn vulkan_present() -> bool {
    requirements()
        .iter()
        .filter(|r| r.what.contains("Vulkan loader") || r.what.contains("lavapipe"))
        .all(|r| r.present)
}

pub(crate) fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

pub(crate) fn install_command() -> String {
    format!(
        "apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y {}",
        APT_PACKAGES.join(" ")
    )
}

pub(crate) fn drivers(ci: bool) -> Outcome {
    let missing = |reqs: &[Requirement]| -> Vec<&'static str> {
        reqs.iter().filter(|r| !r.present).map(|r| r.what).collect()
    };
    let reqs = requirements();
    for r in &reqs {
        println!(
            "  {:8} {}",
            if r.present { "found" } else { "MISSING" },
            r.what
        );
    }
    let mut absent = missing(&reqs);
    if absent.is_empty() {
        return Outcome::Passed;
    }
    if is_root() {
        println!("  installing as root: {}", install_command());
        let ok = Command::new("apt-get")
            .arg("update")
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .is_ok_and(|s| s.success())
            && Command::new("apt-get")
                .args(["install", "-y", "--no-install-recommends"])
                .args(APT_PACKAGES)
                .env("DEBIAN_FRONTEND", "noninteractive")
                .status()
                .is_ok_and(|s| s.success());
        if !ok {
            println!("  apt-get failed");
        }
        absent = missing(&requirements());
        if absent.is_empty() {
            return Outcome::Passed;
        }
    } else {
        println!(
            "  not root: install the drivers with\n    sudo sh -c '{}'",
            install_command()
        );
    }
    let msg = format!("missing: {}", absent.join("; "));
    if ci {
        Outcome::Failed(format!("{msg} (CI=true: the GPU backends must run)"))
    } else {
        println!("  continuing: backends that need them will be skipped visibly");
        Outcome::Warned(msg)
    }
}
