# Warnings and build speed settings shared by every target.
add_compile_options(-Wall -Wextra)
# ASan + UBSan for the fuzz runs outside CI (tests/fuzz/fuzz_main.cc): cmake -DSCANREG_SANITIZE=ON.
option(SCANREG_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
if(SCANREG_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
find_program(CCACHE_PROGRAM ccache)
if(CCACHE_PROGRAM)
  set(CMAKE_CXX_COMPILER_LAUNCHER ${CCACHE_PROGRAM})
  set(CMAKE_C_COMPILER_LAUNCHER ${CCACHE_PROGRAM})
endif()
# Eigen's fixed-size types in std::vector need C++17 aligned new; it is on by default with -std=c++17.

# scanreg_core_library(NAME SOURCES... PUBLIC_LINKS ... PRIVATE_LINKS ...)
function(scanreg_core_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LINKS;PRIVATE_LINKS" ${ARGN})
  add_library(scanreg_${name} STATIC ${ARG_SOURCES})
  add_library(scanreg::${name} ALIAS scanreg_${name})
  target_include_directories(scanreg_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(scanreg_${name} PUBLIC ${ARG_PUBLIC_LINKS} PRIVATE ${ARG_PRIVATE_LINKS})
endfunction()
