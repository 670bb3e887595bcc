#!/usr/bin/env bash
# The installed libraries' symbols: the static library defines no global symbol but
#   - xyl_NAME, declared with XYL_API in an installed header (the public API),
#   - xyl__NAME (library-internal; hidden, so the shared library does not export it),
#   - weak instances of templates and exception-type references that the C++ shims take from
#     the headers of the C++ library, OpenSubdiv and Dragonbox (folded with the user's copies),
# and the shared library exports the public API only.
# symbols.sh <install prefix>
set -euo pipefail
prefix=$1
lib=$(ls "$prefix"/lib*/libxylem.a | head -n 1)
so=$(ls "$prefix"/lib*/libxylem.so | head -n 1)
headers=("$prefix"/include/xylem/*.h)
public=$(cat "${headers[@]}" | tr -s ' \t\n' ' ' | grep -oE 'XYL_API [^;{]*\(' |
         grep -oE 'xyl_[A-Za-z0-9_]+ *\($' | tr -d ' (' | sort -u)
bad=0
checked=0
while read -r type name; do
  checked=$((checked + 1))
  case "$name" in
    xyl__*) continue ;;
    xyl_*)
      if ! grep -qxF "$name" <<<"$public"; then
        echo "symbols: $name is global in libxylem.a but no installed header declares it"; bad=1
      fi
      continue ;;
  esac
  if [[ "$type" =~ ^[WVu]$ ]]; then
    plain=$(c++filt "${name#DW.ref.}")
    # Template instances from those headers, whatever their return type; type information the
    # compiler emits for exceptions and, under UBSan, for every function type called through a
    # pointer; the C++ personality routine's reference and clang's terminate helper; the
    # inline placement new of <new>, which an unoptimised build emits as a weak function.
    if [[ "$plain" =~ ^([^\(]*\ )?(std|__gnu_cxx|OpenSubdiv|jkj::dragonbox)(::|\ ) ]] ||
       [[ "$plain" =~ ^typeinfo\ (name\ )?for\  ]] ||
       [[ "$plain" == __gxx_personality_v0 || "$plain" == __clang_call_terminate ]] ||
       [[ "$plain" == "operator new(unsigned long, void*)" ]]; then
      continue
    fi
  fi
  echo "symbols: libxylem.a defines the global symbol $name ($type): not xyl_-prefixed"; bad=1
done < <(nm -g --defined-only "$lib" | awk 'NF == 3 {print $2, $3}' | sort -u)

while read -r name; do
  checked=$((checked + 1))
  if ! grep -qxF "$name" <<<"$public"; then
    echo "symbols: libxylem.so exports $name, which is not public API"; bad=1
  fi
done < <(nm -D --defined-only "$so" | awk 'NF == 3 && $2 ~ /[TDBR]/ {print $3}' | sort -u)

exported=$(nm -D --defined-only "$so" | awk 'NF == 3 && $2 ~ /[TDBR]/' | wc -l)
echo "symbols: $checked symbols checked, $(wc -l <<<"$public") public functions, $exported exported"
if [ "$exported" -lt "$(wc -l <<<"$public")" ]; then
  echo "symbols: libxylem.so exports fewer functions than the headers declare"; bad=1
fi
exit $bad
