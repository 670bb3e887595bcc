# cmake -DOUT=file -DPREFIX_FILE=p -DIN="a;b" -P xyl_concat.cmake: PREFIX_FILE then the inputs.
file(READ "${PREFIX_FILE}" text)
foreach(f IN LISTS IN)
  file(READ "${f}" part)
  string(APPEND text "${part}")
endforeach()
file(WRITE "${OUT}.tmp" "${text}")
file(RENAME "${OUT}.tmp" "${OUT}")
