# SPDX-License-Identifier: MIT
# `cpack` in the build directory: Debian packages of the install components,
#   fdsurf_<version>_<arch>.deb      the tool (bin/fdsurf), "tool" component
#   fdsurf-dev_<version>_<arch>.deb  libraries, headers, CMake and pkg-config
#                                    packages, "dev" component
# Installed under /usr. Runtime dependencies come from dpkg-shlibdeps.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME fdsurf)
set(CPACK_PACKAGE_VENDOR "The fdsurf authors")
set(CPACK_PACKAGE_CONTACT "fdsurf maintainers <maintainers@users.noreply.h-seed-50ee3156.example>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL tool dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_TOOL_PACKAGE_NAME fdsurf)
set(CPACK_DEBIAN_TOOL_PACKAGE_SHLIBDEPS ON)
set(CPACK_COMPONENT_TOOL_DESCRIPTION
    "fdsurf: bicubic patches evaluated by fixed-point forward differences\n\
Samples, checks, plots (SVG, G-code, HPGL, PNG) and streams patch files to a plotter.")
set(CPACK_DEBIAN_DEV_PACKAGE_NAME fdsurf-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# Static libraries: what their users link against.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "libcairo2-dev, libpugixml-dev, pkg-config")
set(CPACK_DEBIAN_DEV_PACKAGE_SUGGESTS "libusb-1.0-0-dev, libgpiod-dev, libserialport-dev")
set(CPACK_COMPONENT_DEV_DESCRIPTION
    "fdsurf static libraries and headers\n\
The freestanding core (fdsurf::core, fdsurf::hal) and the host library (fdsurf::host), with \
CMake (find_package(fdsurf)) and pkg-config (fdsurf, fdsurf-host) packages.")
include(CPack)
