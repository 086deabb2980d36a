# cmake -DIN=<file.cl> -DOUT=<file.cpp> -DNAME=<name> -P EmfEmbedKernelScript.cmake
# Inlines `#include "x.clh"` lines (relative to the .cl's folder, each header once), hashes the
# result and writes it as a raw string literal.

get_filename_component(dir ${IN} DIRECTORY)
set(EMF_SEEN "")

function(emf_inline path out_var)
  file(READ ${path} text)
  string(REPLACE "\r\n" "\n" text "${text}")
  string(REGEX MATCHALL "#include[ \t]*\"[^\"]+\"" incs "${text}")
  foreach(inc ${incs})
    string(REGEX REPLACE "#include[ \t]*\"([^\"]+)\"" "\\1" hdr "${inc}")
    list(FIND EMF_SEEN ${hdr} seen)
    if(seen EQUAL -1)
      set(EMF_SEEN ${EMF_SEEN} ${hdr} PARENT_SCOPE)
      list(APPEND EMF_SEEN ${hdr})
      if(NOT EXISTS ${dir}/${hdr})
        message(FATAL_ERROR "${path}: #include \"${hdr}\" not found in ${dir}")
      endif()
      emf_inline(${dir}/${hdr} sub)
      string(REPLACE "${inc}" "// ---- begin ${hdr}\n${sub}\n// ---- end ${hdr}" text "${text}")
    else()
      string(REPLACE "${inc}" "// (${hdr} already included)" text "${text}")
    endif()
  endforeach()
  set(${out_var} "${text}" PARENT_SCOPE)
endfunction()

emf_inline(${IN} source)
string(SHA256 hash "${source}")
if(source MATCHES "\\)EMFCL\"")
  message(FATAL_ERROR "${IN}: contains the raw-string delimiter )EMFCL\"")
endif()
file(WRITE ${OUT}.tmp
"// Generated from ${IN} by cmake/EmfEmbedKernelScript.cmake. Do not edit.
#include \"cl/embedded_kernels.h\"

namespace emf::cl::embedded {
extern const KernelSource kKernel_${NAME};
const KernelSource kKernel_${NAME} = {\"${NAME}\", R\"EMFCL(${source})EMFCL\", \"${hash}\"};
}  // namespace emf::cl::embedded
")
file(RENAME ${OUT}.tmp ${OUT})
