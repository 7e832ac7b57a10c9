/* Calls malloc and free on purpose: the heap check must flag this library,
 * or the check itself is broken. Never linked into anything. */
#include <stdlib.h>

void *hstpf_heap_canary_get(size_t n);
void hstpf_heap_canary_put(void *p);

void *hstpf_heap_canary_get(size_t n)
{
    return malloc(n);
}

void hstpf_heap_canary_put(void *p)
{
    free(p);
}
