#!/usr/bin/env bash
# Installs the system packages splitray needs on Debian 12 (bookworm), as root.
#
# lavapipe (mesa-vulkan-drivers) comes from bookworm-backports when that suite can be
# reached: Mesa 25.0's lavapipe traces ~1.2x and sorts ~2.2x faster than bookworm's 22.3
# and adds VK_KHR_ray_query. The backports source is derived from the machine's own
# Debian entry, so no mirror host is written into the project. If backports cannot be
# had, the stock 22.3 driver is installed instead; the engine works on both.
#
# Idempotent: does nothing (and needs no network) when everything is already present.
set -euo pipefail

# fonts-dejavu-core: a sans-serif font for the labels of `splitray timeline -o X.png`.
# The preview window (`render --preview`): the X libraries winit loads at run time
# (libx11-xcb1, libxcursor1, libxi6, libxkbcommon-x11-0); xvfb for the test that opens
# it on a virtual display; x11-apps (xwd) and imagemagick to capture a window by hand.
packages=(
  libvulkan1 libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
  libshaderc-dev glslang-dev spirv-tools pkg-config fonts-dejavu-core
  libx11-xcb1 libxcursor1 libxi6 libxkbcommon-x11-0 xvfb x11-apps imagemagick
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
mesa_from_backports() {
  dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | grep -q bpo
}
if [ ${#missing[@]} -eq 0 ] && { mesa_from_backports || [ -f /etc/apt/.splitray-no-backports ]; }; then
  exit 0
fi

if [ "$(id -u)" -ne 0 ]; then
  sudo=sudo
else
  sudo=
fi

backports_list=/etc/apt/sources.list.d/splitray-bookworm-backports.sources
if [ ! -f "$backports_list" ]; then
  # Take the URI of the main Debian archive from the machine's existing sources.
  uri=""
  if [ -f /etc/apt/sources.list.d/debian.sources ]; then
    uri=$(awk '/^URIs:/ {u=$2} /^Suites:/ && / bookworm( |$)/ && u != "" {print u; exit}' \
      /etc/apt/sources.list.d/debian.sources)
  fi
  if [ -z "$uri" ] && [ -f /etc/apt/sources.list ]; then
    uri=$(awk '$1 == "deb" && $3 == "bookworm" {print $2; exit}' /etc/apt/sources.list)
  fi
  if [ -n "$uri" ]; then
    printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
      "$uri" | $sudo tee "$backports_list" >/dev/null
  else
    echo "install-deps: no bookworm source entry found; using the stock Mesa" >&2
  fi
fi

export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${packages[@]}"
if [ -f "$backports_list" ] && $sudo apt-get install -y -qq --no-install-recommends \
  -t bookworm-backports mesa-vulkan-drivers libvulkan1 2>/dev/null; then
  :
else
  echo "install-deps: Mesa from bookworm-backports unavailable; staying on the stock driver" >&2
  $sudo touch /etc/apt/.splitray-no-backports
fi
