# SPDX-License-Identifier: MIT
# FDSURF_WERROR: -Werror when fdsurf itself is the top-level project (its CI),
# nothing when another project embeds the core with add_subdirectory (a newer
# compiler's new warning must not break someone else's build).
if(NOT DEFINED FDSURF_WERROR)
  get_filename_component(_fdsurf_root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
  if(CMAKE_SOURCE_DIR STREQUAL _fdsurf_root)
    set(FDSURF_WERROR -Werror)
  else()
    set(FDSURF_WERROR "")
  endif()
  unset(_fdsurf_root)
endif()
