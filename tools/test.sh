#!/usr/bin/env bash
# Runs the whole test suite in release mode, installing what it needs first.
#
# The GPU tests run for real on whatever Vulkan adapter is present; on a machine without a GPU
# that is Mesa's lavapipe, installed here from Debian's `mesa-vulkan-drivers` when no Vulkan
# driver is found (as root, or through sudo).
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v cargo >/dev/null 2>&1 && [ -f "$HOME/.cargo/env" ]; then
    # shellcheck disable=SC1091
    . "$HOME/.cargo/env"
fi
command -v cargo >/dev/null 2>&1 || { echo "tools/test.sh: cargo not found; install Rust from https://rustup.rs" >&2; exit 1; }

have_vulkan_driver() {
    local dir
    for dir in /usr/share/vulkan/icd.d /etc/vulkan/icd.d /usr/local/share/vulkan/icd.d; do
        compgen -G "$dir/*.json" >/dev/null && return 0
    done
    [ -n "${VK_ICD_FILENAMES:-}${VK_DRIVER_FILES:-}" ]
}

if ! have_vulkan_driver || ! ldconfig -p 2>/dev/null | grep -q libvulkan.so.1; then
    echo "tools/test.sh: no Vulkan driver found; installing Mesa's lavapipe (mesa-vulkan-drivers)"
    if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq --no-install-recommends mesa-vulkan-drivers libvulkan1 >/dev/null
fi

# The app's tests open a real window on a virtual X server (Xvfb); winit loads the X11
# client libraries at run time.
if ! command -v xvfb-run >/dev/null 2>&1 || ! ldconfig -p 2>/dev/null | grep -q libxkbcommon-x11.so.0; then
    echo "tools/test.sh: installing Xvfb and the X11 client libraries (for the app's window tests)"
    if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq --no-install-recommends xvfb xauth libxkbcommon-x11-0 \
        libx11-xcb1 libxcursor1 libxrandr2 libxi6 >/dev/null
fi

# Mesa's window-system probing complains without a runtime dir; headless runs have none.
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
    XDG_RUNTIME_DIR=$(mktemp -d)
    export XDG_RUNTIME_DIR
    chmod 700 "$XDG_RUNTIME_DIR"
fi

# The Khronos glTF validator checks our glTF exports (tests/import.rs); it comes from npm, so it
# is installed where Node.js is present (it is on our machines) and kept under target/.
validator=target/gltf-validator/node_modules/gltf-validator
if command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1; then
    if [ ! -d "$validator" ]; then
        echo "tools/test.sh: installing the Khronos glTF validator (npm gltf-validator)"
        timeout 300 npm install --silent --no-audit --no-fund --prefix target/gltf-validator gltf-validator@2.0.0-dev.3.10 >/dev/null \
            || echo "tools/test.sh: could not install gltf-validator; glTF exports are checked by our reader only" >&2
    fi
    if [ -d "$validator" ]; then
        export SLAYER_GLTF_VALIDATOR="$PWD/tools/gltf-validate.js"
        export GLTF_VALIDATOR_MODULE="$PWD/$validator"
    fi
else
    echo "tools/test.sh: no Node.js; glTF exports are checked by our reader only (install nodejs and npm for the Khronos validator)" >&2
fi

echo "tools/test.sh: building (release)"
cargo build --release --all-targets --quiet

echo "tools/test.sh: GPU adapters, best first (the GPU tests use the first):"
target/release/slayer adapters | sed 's/^/    /'

# cargo-nextest (on our machines) shares the cores across every test binary and starts the
# longest tests first (.config/nextest.toml); plain cargo test runs the same tests otherwise.
if cargo nextest --version >/dev/null 2>&1; then
    cargo nextest run --release --all-targets --no-fail-fast
else
    echo "tools/test.sh: cargo-nextest not installed; running cargo test (the same tests, one binary at a time)"
    cargo test --release --all-targets
fi
cargo test --release --doc --quiet
echo "tools/test.sh: all tests passed"
