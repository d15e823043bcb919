# Per-ISA compile flags only on the kernel files that need them, chosen by
# the file name's suffix (simd/FAMILY-sse4.c, -avx2.c, -avx512.c);
# everything else, the scalar reference and the dispatch included, stays
# baseline x86-64.
function(vsplat_simd_flags)
  foreach(f ${VSPLAT_KERNEL_SOURCES})
    if(f MATCHES "-sse4\\.c$")
      set_source_files_properties(${f} PROPERTIES COMPILE_OPTIONS "-msse4.1")
    elseif(f MATCHES "-avx2\\.c$")
      set_source_files_properties(${f} PROPERTIES COMPILE_OPTIONS "-mavx2;-mfma")
    elseif(f MATCHES "-avx512\\.c$")
      set_source_files_properties(${f} PROPERTIES COMPILE_OPTIONS "-mavx512f;-mavx512bw;-mavx512dq;-mavx512vl;-mavx2;-mfma")
    endif()
  endforeach()
endfunction()
