/* json_locate.h — where JSON text stops being JSON (not installed), for the
 * line and column of "malformed JSON" messages: cJSON says that parsing
 * failed but its position is sometimes one character past the culprit (a
 * missing key) or at the end of the text. This is a syntax check only
 * (RFC 8259 grammar), run after cJSON has refused the text. */
#ifndef BS_JSON_LOCATE_H
#define BS_JSON_LOCATE_H

/* 1 when the text is not JSON: *at is the first character that cannot
 * continue it (the terminating NUL when the text ends early), *what says
 * what was expected there ("a value", "',' or '}'", ...). 0 when the text
 * is JSON as far as this check sees (*at, *what untouched). Nesting beyond
 * 1000 levels counts as an error. */
int bs__json_locate(const char *text, const char **at, const char **what);

#endif
