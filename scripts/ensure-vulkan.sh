#!/usr/bin/env bash
# Makes sure a Vulkan driver is installed. On a machine without a GPU driver this installs
# Mesa's software Vulkan driver (lavapipe), which runs every kernel and test on the CPU.
set -euo pipefail

has_icd() {
    for dir in /usr/share/vulkan/icd.d /etc/vulkan/icd.d /usr/local/share/vulkan/icd.d; do
        if compgen -G "$dir/*.json" > /dev/null; then
            return 0
        fi
    done
    return 1
}

has_loader() {
    compgen -G "/usr/lib/*/libvulkan.so.1" > /dev/null || compgen -G "/usr/lib*/libvulkan.so.1" > /dev/null \
        || compgen -G "/usr/local/lib/libvulkan.so.1" > /dev/null
}

if has_icd && has_loader; then
    exit 0
fi
install='apt-get update && apt-get install -y mesa-vulkan-drivers'
if [ "$(id -u)" = 0 ] && command -v apt-get > /dev/null; then
    echo "installing the software Vulkan driver: $install" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq mesa-vulkan-drivers > /dev/null
else
    echo "no Vulkan driver found; install one, for example as root: $install" >&2
    exit 1
fi
