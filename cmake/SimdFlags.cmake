# Per-ISA compile flags only on the files that need them (simd/*-sse4.c,
# simd/*-avx2.c, simd/*-avx512.c); everything else stays baseline x86-64.
function(vsplat_simd_flags)
  foreach(f ${VSPLAT_SIMD_SOURCES})
    if(f MATCHES "-sse4\\.c$")
      set_source_files_properties(${f} PROPERTIES COMPILE_OPTIONS "-msse4.1")
    elseif(f MATCHES "-avx2\\.c$")
      set_source_files_properties(${f} PROPERTIES COMPILE_OPTIONS "-mavx2;-mfma")
    elseif(f MATCHES "-avx512\\.c$")
      set_source_files_properties(${f} PROPERTIES COMPILE_OPTIONS "-mavx512f;-mavx512bw;-mavx512dq;-mavx512vl;-mavx2;-mfma")
    endif()
  endforeach()
endfunction()
