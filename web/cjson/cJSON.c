/* cJSON.c - a JSON parser with cJSON's tree and parsing rules (web/cjson/cJSON.h): bytes
 * up to space are whitespace, a UTF-8 byte-order mark is skipped, numbers are the longest
 * run of "0-9+-.eE" read by strtod (as cJSON reads them), strings take the JSON escapes
 * with \u surrogate pairs written as UTF-8, and the error position is where parsing
 * stopped. Every node and string comes from the installed allocator. */
#include "cJSON.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

static cJSON_Hooks hooks = {malloc, free};

void cJSON_InitHooks(cJSON_Hooks *h) {
    hooks.malloc_fn = h && h->malloc_fn ? h->malloc_fn : malloc;
    hooks.free_fn = h && h->free_fn ? h->free_fn : free;
}

typedef struct parser {
    const unsigned char *s;
    size_t len, pos;
    unsigned depth;
} parser;

static int more(const parser *p) {
    return p->pos < p->len;
}

static void skip_space(parser *p) {
    while (more(p) && p->s[p->pos] <= 32) {
        ++p->pos;
    }
}

static cJSON *new_item(void) {
    cJSON *it = hooks.malloc_fn(sizeof *it);
    if (it) {
        memset(it, 0, sizeof *it);
    }
    return it;
}

void cJSON_Delete(cJSON *item) {
    while (item) {
        cJSON *next = item->next;
        cJSON_Delete(item->child);
        if (item->valuestring) {
            hooks.free_fn(item->valuestring);
        }
        if (item->string) {
            hooks.free_fn(item->string);
        }
        hooks.free_fn(item);
        item = next;
    }
}

static int hex4(const unsigned char *h, unsigned *out) {
    unsigned v = 0;
    for (int i = 0; i < 4; ++i) {
        unsigned c = h[i], d;
        if (c >= '0' && c <= '9') {
            d = c - '0';
        } else if (c >= 'a' && c <= 'f') {
            d = c - 'a' + 10;
        } else if (c >= 'A' && c <= 'F') {
            d = c - 'A' + 10;
        } else {
            return 0;
        }
        v = v << 4 | d;
    }
    *out = v;
    return 1;
}

/* A string at p->pos (its opening quote) into a new NUL-terminated buffer. On failure
 * p->pos is where cJSON reports it: the byte after the opening quote (not a string, no
 * closing quote, no memory), or the backslash of a bad escape. */
static char *parse_string_raw(parser *p) {
    const size_t start = p->pos;
    if (!more(p) || p->s[p->pos] != '"') {
        p->pos = start + 1;
        return NULL;
    }
    size_t end = p->pos + 1, extra = 0;
    while (end < p->len && p->s[end] != '"') {
        if (p->s[end] == '\\') {
            if (end + 1 >= p->len) {
                p->pos = start + 1;
                return NULL;
            }
            ++extra;
            ++end;
        }
        ++end;
    }
    if (end >= p->len) {
        p->pos = start + 1;
        return NULL;
    }
    /* Escapes only shrink: the raw length bounds the output. */
    char *out = hooks.malloc_fn(end - p->pos - extra + 1);
    if (!out) {
        p->pos = start + 1;
        return NULL;
    }
    unsigned char *o = (unsigned char *)out;
    size_t i = p->pos + 1, esc = i;
    while (i < end) {
        unsigned char c = p->s[i];
        if (c != '\\') {
            *o++ = c;
            ++i;
            continue;
        }
        esc = i;
        c = p->s[i + 1];
        switch (c) {
        case 'b':
            *o++ = '\b';
            i += 2;
            break;
        case 'f':
            *o++ = '\f';
            i += 2;
            break;
        case 'n':
            *o++ = '\n';
            i += 2;
            break;
        case 'r':
            *o++ = '\r';
            i += 2;
            break;
        case 't':
            *o++ = '\t';
            i += 2;
            break;
        case '"':
        case '\\':
        case '/':
            *o++ = c;
            i += 2;
            break;
        case 'u': {
            unsigned cp, lo;
            if (end - i < 6 || !hex4(p->s + i + 2, &cp) || (cp >= 0xDC00 && cp <= 0xDFFF)) {
                goto fail;
            }
            i += 6;
            if (cp >= 0xD800 && cp <= 0xDBFF) {
                if (end - i < 6 || p->s[i] != '\\' || p->s[i + 1] != 'u' ||
                    !hex4(p->s + i + 2, &lo) || lo < 0xDC00 || lo > 0xDFFF) {
                    goto fail;
                }
                i += 6;
                cp = 0x10000 + ((cp & 0x3FF) << 10 | (lo & 0x3FF));
            }
            if (cp < 0x80) {
                *o++ = (unsigned char)cp;
            } else if (cp < 0x800) {
                *o++ = (unsigned char)(0xC0 | cp >> 6);
                *o++ = (unsigned char)(0x80 | (cp & 0x3F));
            } else if (cp < 0x10000) {
                *o++ = (unsigned char)(0xE0 | cp >> 12);
                *o++ = (unsigned char)(0x80 | (cp >> 6 & 0x3F));
                *o++ = (unsigned char)(0x80 | (cp & 0x3F));
            } else {
                *o++ = (unsigned char)(0xF0 | cp >> 18);
                *o++ = (unsigned char)(0x80 | (cp >> 12 & 0x3F));
                *o++ = (unsigned char)(0x80 | (cp >> 6 & 0x3F));
                *o++ = (unsigned char)(0x80 | (cp & 0x3F));
            }
            break;
        }
        default:
            goto fail;
        }
    }
    *o = '\0';
    p->pos = end + 1;
    return out;
fail:
    hooks.free_fn(out);
    p->pos = esc; /* the escape's backslash */
    return NULL;
}

static int parse_number(parser *p, cJSON *it) {
    char buf[64];
    size_t n = 0;
    while (n + 1 < sizeof buf && p->pos + n < p->len) {
        const unsigned char c = p->s[p->pos + n];
        if (!((c >= '0' && c <= '9') || c == '+' || c == '-' || c == '.' || c == 'e' || c == 'E')) {
            break;
        }
        buf[n++] = (char)c;
    }
    buf[n] = '\0';
    char *stop = NULL;
    const double d = strtod(buf, &stop);
    if (stop == buf) {
        return 0;
    }
    it->type = cJSON_Number;
    it->valuedouble = d;
    it->valueint = d >= INT_MAX ? INT_MAX : d <= (double)INT_MIN ? INT_MIN : (int)d;
    p->pos += (size_t)(stop - buf);
    return 1;
}

static int literal(parser *p, const char *word) {
    const size_t n = strlen(word);
    if (p->len - p->pos >= n && memcmp(p->s + p->pos, word, n) == 0) {
        p->pos += n;
        return 1;
    }
    return 0;
}

static int parse_value(parser *p, cJSON *it);

/* An array or object at p->pos: elements (members, with their keys) linked as children. */
static int parse_list(parser *p, cJSON *it, int object) {
    if (p->depth >= CJSON_NESTING_LIMIT) {
        return 0;
    }
    ++p->depth;
    ++p->pos; /* '[' or '{' */
    it->type = object ? cJSON_Object : cJSON_Array;
    skip_space(p);
    const unsigned char close = object ? '}' : ']';
    if (more(p) && p->s[p->pos] == close) {
        ++p->pos;
        --p->depth;
        return 1;
    }
    cJSON *last = NULL;
    for (;;) {
        cJSON *child = new_item();
        if (!child) {
            return 0;
        }
        if (last) {
            last->next = child;
            child->prev = last;
        } else {
            it->child = child;
        }
        last = child;
        skip_space(p);
        if (object) {
            child->string = parse_string_raw(p);
            if (!child->string) {
                return 0;
            }
            skip_space(p);
            if (!more(p) || p->s[p->pos] != ':') {
                return 0;
            }
            ++p->pos;
            skip_space(p);
        }
        if (!parse_value(p, child)) {
            return 0;
        }
        skip_space(p);
        if (!more(p)) {
            return 0;
        }
        if (p->s[p->pos] == ',') {
            ++p->pos;
            continue;
        }
        if (p->s[p->pos] != close) {
            return 0;
        }
        ++p->pos;
        break;
    }
    /* cJSON keeps the last child in the first one's prev. */
    it->child->prev = last;
    --p->depth;
    return 1;
}

static int parse_value(parser *p, cJSON *it) {
    if (!more(p)) {
        return 0;
    }
    const unsigned char c = p->s[p->pos];
    if (c == 'n' && literal(p, "null")) {
        it->type = cJSON_NULL;
        return 1;
    }
    if (c == 'f' && literal(p, "false")) {
        it->type = cJSON_False;
        return 1;
    }
    if (c == 't' && literal(p, "true")) {
        it->type = cJSON_True;
        it->valueint = 1;
        return 1;
    }
    if (c == '"') {
        it->type = cJSON_String;
        it->valuestring = parse_string_raw(p);
        return it->valuestring != NULL;
    }
    if (c == '-' || (c >= '0' && c <= '9')) {
        return parse_number(p, it);
    }
    if (c == '[' || c == '{') {
        return parse_list(p, it, c == '{');
    }
    return 0;
}

cJSON *cJSON_ParseWithLengthOpts(const char *value, size_t length, const char **return_parse_end,
                                 cJSON_bool require_null_terminated) {
    parser p = {(const unsigned char *)value, value ? length : 0, 0, 0};
    cJSON *root = NULL;
    if (!value || length == 0) {
        goto fail;
    }
    if (p.len >= 3 && memcmp(p.s, "\xEF\xBB\xBF", 3) == 0) {
        p.pos = 3;
    }
    root = new_item();
    if (!root) {
        goto fail;
    }
    skip_space(&p);
    if (!parse_value(&p, root)) {
        goto fail;
    }
    if (require_null_terminated) {
        skip_space(&p);
        if (p.pos >= p.len || p.s[p.pos] != '\0') {
            goto fail;
        }
    }
    if (return_parse_end) {
        *return_parse_end = value + p.pos;
    }
    return root;
fail:
    cJSON_Delete(root);
    if (return_parse_end && value) {
        size_t at = p.pos < p.len ? p.pos : (p.len > 0 ? p.len - 1 : 0);
        *return_parse_end = value + at;
    }
    return NULL;
}

int cJSON_GetArraySize(const cJSON *array) {
    int n = 0;
    for (const cJSON *c = array ? array->child : NULL; c; c = c->next) {
        ++n;
    }
    return n;
}

cJSON *cJSON_GetObjectItemCaseSensitive(const cJSON *object, const char *string) {
    if (!object || !string) {
        return NULL;
    }
    for (cJSON *c = object->child; c; c = c->next) {
        if (c->string && strcmp(c->string, string) == 0) {
            return c;
        }
    }
    return NULL;
}

cJSON_bool cJSON_IsBool(const cJSON *item) {
    return item && (item->type & 0xFF & (cJSON_True | cJSON_False)) != 0;
}
cJSON_bool cJSON_IsTrue(const cJSON *item) {
    return item && (item->type & 0xFF) == cJSON_True;
}
cJSON_bool cJSON_IsNull(const cJSON *item) {
    return item && (item->type & 0xFF) == cJSON_NULL;
}
cJSON_bool cJSON_IsNumber(const cJSON *item) {
    return item && (item->type & 0xFF) == cJSON_Number;
}
cJSON_bool cJSON_IsString(const cJSON *item) {
    return item && (item->type & 0xFF) == cJSON_String;
}
cJSON_bool cJSON_IsArray(const cJSON *item) {
    return item && (item->type & 0xFF) == cJSON_Array;
}
cJSON_bool cJSON_IsObject(const cJSON *item) {
    return item && (item->type & 0xFF) == cJSON_Object;
}
