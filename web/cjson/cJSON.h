/* cJSON.h - the part of cJSON's interface (https://github.com/DaveGamble/cJSON, the
 * library the native build links) that src/scene/json.c uses, for the web build:
 * Emscripten cannot link Debian's libcjson, so web/cjson/cJSON.c parses the same grammar
 * into the same tree. Only parsing and reading are provided. */
#ifndef TR_WEB_CJSON_H
#define TR_WEB_CJSON_H

#include <stddef.h>

#define cJSON_Invalid (0)
#define cJSON_False (1 << 0)
#define cJSON_True (1 << 1)
#define cJSON_NULL (1 << 2)
#define cJSON_Number (1 << 3)
#define cJSON_String (1 << 4)
#define cJSON_Array (1 << 5)
#define cJSON_Object (1 << 6)

/* The deepest nesting of arrays and objects the parser accepts (cJSON's default). */
#define CJSON_NESTING_LIMIT 1000

typedef int cJSON_bool;

typedef struct cJSON {
    struct cJSON *next, *prev; /* siblings in an array or object */
    struct cJSON *child;       /* the first element or member */
    int type;
    char *valuestring; /* cJSON_String */
    int valueint;      /* valuedouble saturated to int */
    double valuedouble;
    char *string; /* the member's key inside an object */
} cJSON;

typedef struct cJSON_Hooks {
    void *(*malloc_fn)(size_t sz);
    void (*free_fn)(void *ptr);
} cJSON_Hooks;

void cJSON_InitHooks(cJSON_Hooks *hooks);
/* Parses `length` bytes at value; NULL on a syntax error (or failed allocation), with
 * *return_parse_end at the byte where parsing stopped. Text after the value is allowed
 * unless require_null_terminated. */
cJSON *cJSON_ParseWithLengthOpts(const char *value, size_t length, const char **return_parse_end,
                                 cJSON_bool require_null_terminated);
void cJSON_Delete(cJSON *item);
int cJSON_GetArraySize(const cJSON *array);
cJSON *cJSON_GetObjectItemCaseSensitive(const cJSON *object, const char *string);
cJSON_bool cJSON_IsBool(const cJSON *item);
cJSON_bool cJSON_IsTrue(const cJSON *item);
cJSON_bool cJSON_IsNull(const cJSON *item);
cJSON_bool cJSON_IsNumber(const cJSON *item);
cJSON_bool cJSON_IsString(const cJSON *item);
cJSON_bool cJSON_IsArray(const cJSON *item);
cJSON_bool cJSON_IsObject(const cJSON *item);

#endif
