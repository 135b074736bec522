/* Exports Embree's header-only (RTC_FORCEINLINE) helpers as real symbols so
 * Rust can call them. Compiled against the installed headers by build.rs, so
 * the struct layouts always match the installed library. build.rs defines
 * EMBREE_SYS_4 or EMBREE_SYS_3 for the version it found. */
#ifdef EMBREE_SYS_4
#include <embree4/rtcore.h>

void embree_sys_rtcInitIntersectArguments(struct RTCIntersectArguments *args)
{
  rtcInitIntersectArguments(args);
}

void embree_sys_rtcInitOccludedArguments(struct RTCOccludedArguments *args)
{
  rtcInitOccludedArguments(args);
}
#else
#include <embree3/rtcore.h>

void embree_sys_rtcInitIntersectContext(struct RTCIntersectContext *context)
{
  rtcInitIntersectContext(context);
}
#endif
