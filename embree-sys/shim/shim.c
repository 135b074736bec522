/* Exports Embree's header-only (RTC_FORCEINLINE) helpers as real symbols so
 * Rust can call them. Compiled against the installed headers by build.rs, so
 * the struct layouts always match the installed library. */
#include <embree3/rtcore.h>

void embree_sys_rtcInitIntersectContext(struct RTCIntersectContext *context)
{
  rtcInitIntersectContext(context);
}
