# `cmake --install` and `cpack`: the command, libchatterlab, the public headers, the CMake package
# (find_package(chatterlab) with exported targets and chatterlab_add_plugin), shell completion,
# the documentation and the shipped studies. Nothing installed names the source or build tree:
# the tests/sdk test checks the installed files for it.
include(CMakePackageConfigHelpers)

set(chatterlab_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/chatterlab)
set(chatterlab_private_libdir ${CMAKE_INSTALL_LIBDIR}/chatterlab)

# Installed binaries find libchatterlab (and it its bundled libraries) relative to themselves, so
# the installed tree can be moved (a .deb, a prefix in the home directory).
file(RELATIVE_PATH chatterlab_lib_from_bin ${CMAKE_INSTALL_FULL_BINDIR} ${CMAKE_INSTALL_FULL_LIBDIR})
set_target_properties(chatterlab PROPERTIES INSTALL_RPATH "$ORIGIN/${chatterlab_lib_from_bin}")

# The optimised SUNDIALS of build/deps (top-level CMakeLists.txt) is what the library was linked
# against: install it beside libchatterlab, privately, so the installed chatterlab is as fast as
# the build tree's (Debian's own SUNDIALS is compiled at -O0 and has the same sonames). Their
# build-time RUNPATH (an absolute path into the source tree) is replaced by $ORIGIN.
# chatterlab_install_private_sundials(DIR [install options]) installs them into DIR (relative to
# the prefix): libchatterlab's directory + "/chatterlab". python/CMakeLists.txt uses it for the
# Python package, with "COMPONENT python EXCLUDE_FROM_ALL".
function(chatterlab_install_private_sundials dir)
  if(NOT SUNDIALS_DIR STREQUAL CHATTERLAB_OPTIMISED_SUNDIALS)
    return()
  endif()
  foreach(library IN ITEMS cvode arkode nvecserial)
    get_target_property(location SUNDIALS::${library}_shared IMPORTED_LOCATION_RELEASE)
    get_target_property(soname SUNDIALS::${library}_shared IMPORTED_SONAME_RELEASE)
    get_filename_component(real_name ${location} NAME)
    install(FILES ${location} DESTINATION ${dir} ${ARGN})
    install(CODE "
      set(installed \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${dir}\")
      file(RPATH_SET FILE \"\${installed}/${real_name}\" NEW_RPATH \"\\\$ORIGIN\")
      file(CREATE_LINK ${real_name} \"\${installed}/${soname}\" SYMBOLIC)" ${ARGN})
  endforeach()
endfunction()
if(SUNDIALS_DIR STREQUAL CHATTERLAB_OPTIMISED_SUNDIALS)
  set_target_properties(libchatterlab PROPERTIES INSTALL_RPATH "$ORIGIN/chatterlab")
endif()
chatterlab_install_private_sundials(${chatterlab_private_libdir})

install(TARGETS libchatterlab chatterlab EXPORT chatterlabTargets
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/framework/include/chatterlab
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES ${PROJECT_BINARY_DIR}/framework/include/chatterlab/version.hpp
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/chatterlab)

install(EXPORT chatterlabTargets NAMESPACE chatterlab:: DESTINATION ${chatterlab_cmake_dir})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/chatterlabConfig.cmake.in
  ${PROJECT_BINARY_DIR}/chatterlabConfig.cmake INSTALL_DESTINATION ${chatterlab_cmake_dir})
# Before 1.0 a minor release may change the plugin ABI: a plugin asks for the same major.minor.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/chatterlabConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/chatterlabConfig.cmake
              ${PROJECT_BINARY_DIR}/chatterlabConfigVersion.cmake
              ${CMAKE_CURRENT_LIST_DIR}/chatterlab_add_plugin.cmake
        DESTINATION ${chatterlab_cmake_dir})

# Shell completion, where bash-completion and zsh look for it.
install(FILES ${PROJECT_SOURCE_DIR}/framework/cli/completion/chatterlab.bash
        DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions RENAME chatterlab)
install(FILES ${PROJECT_SOURCE_DIR}/framework/cli/completion/_chatterlab
        DESTINATION ${CMAKE_INSTALL_DATADIR}/zsh/vendor-completions)

install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/studies/ DESTINATION ${CMAKE_INSTALL_DATADIR}/chatterlab/studies)

# ---- cpack: a Debian package (cpack -G DEB in the build directory)
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME chatterlab)
set(CPACK_PACKAGE_VENDOR "chatterlab")
set(CPACK_PACKAGE_CONTACT "chatterlab maintainers <chatterlab@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "chatter and stability analysis for grinding, with an SDK for plugins")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# Run-time libraries from dpkg-shlibdeps (the bundled SUNDIALS resolves inside the package);
# the SDK needs a compiler, CMake and the JSON headers; plots need gnuplot, `mpirun` Open MPI.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS
    ${CPACK_PACKAGING_INSTALL_PREFIX}/${chatterlab_private_libdir})
set(CPACK_DEBIAN_PACKAGE_DEPENDS "gnuplot-nox | gnuplot, nlohmann-json3-dev (>= 3)")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "cmake (>= 3.25), g++ (>= 12), openmpi-bin, bash-completion")
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
include(CPack)
