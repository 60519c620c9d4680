// Valid PDUs of every function code (hex). Shared by the round-trip and allocation tests;
// fuzz/make_corpus.py reads the string literals between the BEGIN/END markers to seed the
// fuzz corpora, so keep one PDU per literal.
#pragma once

namespace mbstorm::codec::test {

// BEGIN REQUESTS
inline constexpr const char* kValidRequests[] = {
    "01 00 13 00 25",
    "01 00 00 07 D0",
    "02 00 C4 00 16",
    "03 00 6B 00 03",
    "03 00 00 00 7D",
    "03 FF FF 00 01",
    "04 00 08 00 01",
    "05 00 AC FF 00",
    "05 00 01 00 00",
    "06 00 01 00 03",
    "07",
    "08 00 00 A5 37",
    "08 00 00",
    "08 00 01 FF 00",
    "08 00 0A 00 00",
    "08 00 14 00 00",
    "0B",
    "0C",
    "0F 00 13 00 0A 02 CD 01",
    "10 00 01 00 02 04 00 0A 01 02",
    "11",
    "14 0E 06 00 04 00 01 00 02 06 00 03 00 09 00 02",
    "15 0D 06 00 04 00 07 00 03 06 AF 04 BE 10 0D",
    "16 00 04 00 F2 00 25",
    "17 00 03 00 06 00 0E 00 03 06 00 FF 00 FF 00 FF",
    "18 04 DE",
    "2B 0E 01 00",
    "2B 0E 04 81",
};
// END REQUESTS

// BEGIN RESPONSES
inline constexpr const char* kValidResponses[] = {
    "01 05 CD 6B B2 0E 1B",
    "02 03 AC DB 35",
    "03 06 02 2B 00 00 00 64",
    "04 02 00 0A",
    "05 00 AC FF 00",
    "06 00 01 00 03",
    "07 6D",
    "08 00 00 A5 37",
    "08 00 0B 01 2C",
    "0B FF FF 01 08",
    "0C 08 00 00 01 08 01 21 20 00",
    "0F 00 13 00 0A",
    "10 00 01 00 02",
    "11 03 0A FF 42",
    "14 0C 05 06 0D FE 00 20 05 06 33 CD 00 40",
    "15 0D 06 00 04 00 07 00 03 06 AF 04 BE 10 0D",
    "16 00 04 00 F2 00 25",
    "17 0C 00 FE 0A CD 00 01 00 03 00 0D 00 FF",
    "18 00 06 00 02 01 B8 12 84",
    "2B 0E 01 01 00 00 03 00 05 41 42 43 44 45 01 02 50 31 02 03 56 31 2E",
    "81 01",
    "83 02",
    "90 03",
    "AB 04",
    "86 05",
    "85 06",
    "94 08",
    "84 0A",
    "83 0B",
};
// END RESPONSES

}  // namespace mbstorm::codec::test
