# Install rules and the relocatable CMake package:
#   find_package(stabint)  +  target_link_libraries(app PRIVATE stabint::stabint)
#
# Layout under the prefix (GNUInstallDirs):
#   lib/libstabint.a (or lib/libstabint.so* with BUILD_SHARED_LIBS), include/stabint/*.hpp,
#   bin/stabint-run, lib/cmake/stabint/{stabintConfig,stabintConfigVersion,stabintTargets*,
#   FindCHOLMOD}.cmake
#
# A static libstabint's private dependencies (CHOLMOD, OpenCL) end up on the consumer's link line
# as $<LINK_ONLY:...>: the config file finds them again, with the FindCHOLMOD module installed
# next to it (Debian's SuiteSparse has no CMake config). A shared libstabint carries them itself
# (its DT_NEEDED entries), so the consumer needs neither their headers nor their CMake modules.
# nlohmann_json is header-only and used only inside the library's sources, so it is a
# build-tree dependency only.
include(CMakePackageConfigHelpers)

set(STABINT_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/stabint" CACHE STRING
    "Where the stabint CMake package files are installed, relative to the prefix")

install(TARGETS stabint
  EXPORT stabintTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})  # include dir: INSTALL_INTERFACE of the target
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/stabint)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/stabint
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  FILES_MATCHING PATTERN "*.hpp" PATTERN "*.h")

if(TARGET stabint-run)
  install(TARGETS stabint-run RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

install(EXPORT stabintTargets
  NAMESPACE stabint::
  FILE stabintTargets.cmake
  DESTINATION ${STABINT_INSTALL_CMAKEDIR})

configure_package_config_file(
  ${PROJECT_SOURCE_DIR}/cmake/stabintConfig.cmake.in
  ${PROJECT_BINARY_DIR}/stabintConfig.cmake
  INSTALL_DESTINATION ${STABINT_INSTALL_CMAKEDIR})
write_basic_package_version_file(
  ${PROJECT_BINARY_DIR}/stabintConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)  # 0.x: minor versions may change the API
install(FILES
  ${PROJECT_BINARY_DIR}/stabintConfig.cmake
  ${PROJECT_BINARY_DIR}/stabintConfigVersion.cmake
  ${PROJECT_SOURCE_DIR}/cmake/FindCHOLMOD.cmake
  DESTINATION ${STABINT_INSTALL_CMAKEDIR})
