# SPDX-License-Identifier: MIT
# Install rules and the packages for other projects (docs/embedding.md):
#   <prefix>/include/fdsurf/...            every box's public headers
#   <prefix>/lib/libfdsurf_*.a             the static libraries
#   <prefix>/lib/cmake/fdsurf/             find_package(fdsurf): fdsurf::core,
#                                          fdsurf::hal, and in a full build
#                                          fdsurf::host, fdsurf::host_link and
#                                          the HAL backends
#   <prefix>/lib/pkgconfig/fdsurf.pc       the core (+ fdsurf-host.pc)
#   <prefix>/bin/fdsurf                    the tool (full build)
# Components: "dev" (libraries, headers, packages) and "tool" (the tool).
include(CMakePackageConfigHelpers)

set(FDSURF_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/fdsurf)
set(FDSURF_PACKAGE_HOST OFF)
set(FDSURF_PACKAGE_DEVICE OFF)

# The freestanding core: always.
install(TARGETS fdsurf_hal fdsurf_core EXPORT fdsurfTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/hal/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        COMPONENT dev)
foreach(box engine protocol motion device)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/firmware/${box}/include/
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dev)
endforeach()

if(TARGET fdsurf_host)
  set(FDSURF_PACKAGE_HOST ON)
  # The host library and the host-side HAL backends without outside
  # libraries (fdsurf_hal_sim: in-memory test doubles; fdsurf_hal_linux: the
  # CLOCK_MONOTONIC clock).
  install(TARGETS fdsurf_host fdsurf_host_link fdsurf_hal_sim fdsurf_hal_linux
          EXPORT fdsurfTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
  foreach(dir host/core host/reference host/formats host/constructions host/toolpath host/stream
              host/link hal/sim hal/linux)
    install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
            COMPONENT dev)
  endforeach()
  # The backends that need libusb-1.0, libgpiod and libserialport: their own
  # export set, so find_package(fdsurf) offers them only where those
  # libraries are found.
  set(FDSURF_PACKAGE_DEVICE ON)
  install(TARGETS fdsurf_hal_usb fdsurf_hal_gpiod fdsurf_hal_serial EXPORT fdsurfDeviceTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
  foreach(dir hal/libusb hal/libgpiod hal/libserialport)
    install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
            COMPONENT dev)
  endforeach()
  install(EXPORT fdsurfDeviceTargets NAMESPACE fdsurf:: DESTINATION ${FDSURF_CMAKE_DIR}
          COMPONENT dev)
endif()

if(TARGET fdsurf)
  install(TARGETS fdsurf RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT tool)
  install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT tool)
endif()

install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/fdsurf-dev
        COMPONENT dev)
install(EXPORT fdsurfTargets NAMESPACE fdsurf:: DESTINATION ${FDSURF_CMAKE_DIR} COMPONENT dev)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/fdsurfConfig.cmake.in
  ${PROJECT_BINARY_DIR}/fdsurfConfig.cmake INSTALL_DESTINATION ${FDSURF_CMAKE_DIR})
# 0.y releases may change the API from one minor version to the next.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/fdsurfConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/fdsurfConfig.cmake ${PROJECT_BINARY_DIR}/fdsurfConfigVersion.cmake
        DESTINATION ${FDSURF_CMAKE_DIR} COMPONENT dev)

# pkg-config: relocatable (the prefix is found from the .pc file's own place),
# so `cmake --install --prefix DIR` and the .deb both get working paths.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}" OR IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(FDSURF_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
else()
  set(FDSURF_PC_PREFIX "\${pcfiledir}/..")
  string(REPLACE "/" ";" libdir_parts "${CMAKE_INSTALL_LIBDIR}")
  foreach(part ${libdir_parts})
    string(APPEND FDSURF_PC_PREFIX "/..")
  endforeach()
endif()
foreach(dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${dir}}")
    set(FDSURF_PC_${dir} "${CMAKE_INSTALL_${dir}}")
  else()
    set(FDSURF_PC_${dir} "\${prefix}/${CMAKE_INSTALL_${dir}}")
  endif()
endforeach()
configure_file(${CMAKE_CURRENT_LIST_DIR}/fdsurf.pc.in ${PROJECT_BINARY_DIR}/fdsurf.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/fdsurf.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig
        COMPONENT dev)
if(FDSURF_PACKAGE_HOST)
  configure_file(${CMAKE_CURRENT_LIST_DIR}/fdsurf-host.pc.in ${PROJECT_BINARY_DIR}/fdsurf-host.pc
                 @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/fdsurf-host.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig
          COMPONENT dev)
endif()
