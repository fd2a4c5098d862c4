/* json_locate.c — the first syntax error of JSON text (json_locate.h): a
 * recursive descent over the RFC 8259 grammar that builds nothing. */
#include <string.h>

#include "json_locate.h"

typedef struct scan {
  const char *p;
  const char *at, *what; /* the first error */
  int depth;
} scan;

static int err(scan *s, const char *what) {
  if (!s->at) {
    s->at = s->p;
    s->what = what;
  }
  return 1;
}

static void ws(scan *s) {
  while (*s->p == ' ' || *s->p == '\t' || *s->p == '\n' || *s->p == '\r') s->p++;
}

static int is_digit(char c) { return c >= '0' && c <= '9'; }

static int string(scan *s) {
  if (*s->p != '"') return err(s, "a string");
  const char *open = s->p++;
  for (;;) {
    unsigned char c = (unsigned char)*s->p;
    if (c == '"') break;
    if (c == '\0' || c == '\n' || c == '\r') { /* the string runs off its line */
      s->p = open;
      return err(s, "a closing quote for this string");
    }
    if (c < 0x20) return err(s, "no control character inside a string (\\t for a tab)");
    if (c == '\\') {
      s->p++;
      if (*s->p == 'u') {
        for (int i = 1; i <= 4; i++)
          if (!strchr("0123456789abcdefABCDEF", s->p[i]) || !s->p[i]) return s->p += i, err(s, "4 hex digits after \\u");
        s->p += 4;
      } else if (!*s->p || !strchr("\"\\/bfnrt", *s->p)) {
        return err(s, "an escape (\\\" \\\\ \\/ \\b \\f \\n \\r \\t \\uXXXX)");
      }
    }
    s->p++;
  }
  s->p++;
  return 0;
}

static int number(scan *s) {
  if (*s->p == '-') s->p++;
  if (*s->p == '0') s->p++;
  else if (is_digit(*s->p))
    while (is_digit(*s->p)) s->p++;
  else return err(s, "a digit");
  if (*s->p == '.') {
    s->p++;
    if (!is_digit(*s->p)) return err(s, "a digit after the decimal point");
    while (is_digit(*s->p)) s->p++;
  }
  if (*s->p == 'e' || *s->p == 'E') {
    s->p++;
    if (*s->p == '+' || *s->p == '-') s->p++;
    if (!is_digit(*s->p)) return err(s, "a digit in the exponent");
    while (is_digit(*s->p)) s->p++;
  }
  return 0;
}

static int value(scan *s);

/* The members of an object or the elements of an array, after the opening
 * bracket: `close` is '}' or ']'. */
static int members(scan *s, char close) {
  int obj = close == '}';
  ws(s);
  if (*s->p == close) return s->p++, 0;
  for (;;) {
    ws(s);
    if (obj) {
      if (*s->p != '"') return err(s, "a key in double quotes");
      if (string(s)) return 1;
      ws(s);
      if (*s->p != ':') return err(s, "':' after the key");
      s->p++;
    }
    if (value(s)) return 1;
    ws(s);
    if (*s->p == ',') {
      s->p++;
      continue;
    }
    if (*s->p == close) return s->p++, 0;
    return err(s, obj ? "',' or '}'" : "',' or ']'");
  }
}

static int value(scan *s) {
  ws(s);
  char c = *s->p;
  if (c == '{' || c == '[') {
    if (++s->depth > 1000) return err(s, "less nesting (at most 1000 levels)");
    s->p++;
    int st = members(s, c == '{' ? '}' : ']');
    s->depth--;
    return st;
  }
  if (c == '"') return string(s);
  if (c == '-' || is_digit(c)) return number(s);
  static const char *const words[] = {"true", "false", "null"};
  for (int i = 0; i < 3; i++)
    if (!strncmp(s->p, words[i], strlen(words[i]))) return s->p += strlen(words[i]), 0;
  return err(s, "a value (an object, array, string, number, true, false or null)");
}

int bs__json_locate(const char *text, const char **at, const char **what) {
  scan s = {text, NULL, NULL, 0};
  if (!value(&s)) {
    ws(&s);
    if (!*s.p) return 0;
    err(&s, "the end of the text (one value only)");
  }
  *at = s.at;
  *what = s.what;
  return 1;
}
