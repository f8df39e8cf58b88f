#!/usr/bin/env bash
# lcm-gen for C++, then the two checks its decode() lacks (LCM 1.4, Debian
# 12), so that no packet from the network reaches undefined behaviour:
#  - a string's length (strlen + 1 on the wire, so >= 1) is checked only
#    against the bytes left: 0 or less made assign(p, length - 1) throw
#    std::length_error, and INT32_MIN overflowed the int (found by
#    tests/fuzz/command_auth_fuzz.cpp);
#  - an array's count is not checked at all before resize(): a negative one
#    throws, a huge one allocates gigabytes. Every element takes a byte at
#    least, so a count above the bytes left is malformed.
#  - a string holding a NUL before its end (found by
#    tests/fuzz/lcm_messages_fuzz.cpp): decode() took it whole, but
#    encode() writes strlen() bytes where getEncodedSize() counted size(),
#    so a message that carried one (a relayed string, a JSON "\u0000")
#    encoded short and lcm::LCM::publish() sent the rest of its buffer
#    uninitialised. decode() now refuses such a string, and
#    getEncodedSize() counts what encode() writes (up to the first NUL).
# msgs::decode_message() still catches whatever decode() throws.
#   lcm_gen.sh LCM_GEN OUTDIR FILE.lcm...
set -euo pipefail
lcm_gen=$1 out=$2
shift 2
mkdir -p "$out"
"$lcm_gen" --cpp --cpp-std c++11 --cpp-hpath "$out" "$@"
for lcm in "$@"; do
  type=$(basename "$lcm" .lcm)
  header=$(find "$out" -name "$type.hpp")
  [ -n "$header" ] || { echo "lcm_gen.sh: lcm-gen wrote no $type.hpp" >&2; exit 1; }
  sed -i -E \
    -e 's/if\((__[A-Za-z0-9_]*len_*) > maxlen - pos\) return -1;/if(\1 <= 0 || \1 > maxlen - pos) return -1;/' \
    -e 's/^( *)this->([A-Za-z0-9_]+)\.resize\(this->([A-Za-z0-9_]+)\);/\1if(this->\3 < 0 || this->\3 > maxlen - pos) return -1;\n\1this->\2.resize(this->\3);/' \
    -e 's/^( *)(this->[A-Za-z0-9_]+(\[a[0-9]+\])*\.assign\(\(\(const char\*\)buf\) \+ offset \+ pos, (__[A-Za-z0-9_]+) *- *1\);)/\1if(memchr(((const char*)buf) + offset + pos, 0, \4 - 1)) return -1;\n\1\2/' \
    -e 's/enc_size \+= this->([A-Za-z0-9_]+(\[a[0-9]+\])*)\.size\(\) \+ 4 \+ 1;/enc_size += strlen(this->\1.c_str()) + 4 + 1;/' \
    "$header"
done
