//! `create_backend` without a platform: `Unavailable`, saying why (run in a child process with
//! the ICD loader pointed at an empty vendor directory, so the loader finds no driver).

use shadowvol_silhouette::BackendError;
use shadowvol_test_support::{main, skip, Outcome};
use std::process::Command;

main!(no_platform_is_unavailable_with_a_reason);

const CHILD: &str = "SHADOWVOL_OPENCL_TEST_CHILD";

fn no_platform_is_unavailable_with_a_reason() -> Outcome {
    if std::env::var_os(CHILD).is_some() {
        match shadowvol_opencl::create_backend() {
            Err(BackendError::Unavailable { backend, reason }) => {
                assert_eq!(backend, "opencl");
                println!("REASON: {reason}");
            }
            Ok(b) => println!("STARTED: {}", b.info().device),
            Err(e) => panic!("expected Unavailable, got {e:?}"),
        }
        return Ok(());
    }
    let empty = std::env::temp_dir().join(format!("shadowvol-no-icd-{}", std::process::id()));
    std::fs::create_dir_all(&empty).unwrap();
    let out = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "no_platform_is_unavailable_with_a_reason",
            "--nocapture",
        ])
        .env(CHILD, "1")
        .env("OCL_ICD_VENDORS", &empty)
        .env_remove("OPENCL_DYLIB_PATH")
        .output()
        .unwrap();
    let _ = std::fs::remove_dir(&empty);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "child failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    if stdout.contains("STARTED:") {
        // Not the ocl-icd loader (it ignores OCL_ICD_VENDORS): nothing to check here. CI
        // installs ocl-icd, so there this is a failure (`skip` panics under CI).
        return Err(skip(format!(
            "this ICD loader ignores OCL_ICD_VENDORS: {}",
            stdout.trim()
        )));
    }
    let reason = stdout
        .lines()
        .find_map(|l| l.strip_prefix("REASON: "))
        .unwrap_or_else(|| panic!("no reason printed: {stdout}"));
    // Either the loader is missing, or it found no platform: both name what to install.
    assert!(
        reason.contains("no platform") || reason.contains("no OpenCL ICD loader"),
        "{reason}"
    );
    assert!(reason.contains("pocl-opencl-icd"), "{reason}");
    Ok(())
}
