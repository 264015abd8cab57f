#pragma once
// Every difference between the Wireshark versions the plugin builds for (4.0 to 4.6) that the
// plugin meets, keyed on Wireshark's own version macros (ws_version.h): the plugin calls the
// names here and has no version test of its own. A plugin is built for one major.minor; this
// header only lets the same source build for each.
#include <epan/packet.h>
#include <epan/prefs.h>
#include <epan/proto.h>
#include <epan/stat_tap_ui.h>
#include <epan/stats_tree.h>
#include <epan/tfs.h>  // true_false_string: proto.h no longer brings it in 4.6
#include <epan/tvbuff.h>
#include <epan/uat.h>
#include <wireshark.h>
#include <ws_version.h>

#define NCSERVO_WS_AT_LEAST(major, minor) \
  (WIRESHARK_VERSION_MAJOR > (major) ||   \
   (WIRESHARK_VERSION_MAJOR == (major) && WIRESHARK_VERSION_MINOR >= (minor)))

// From 4.4 the loader asks a plugin what it provides (`tshark -G plugins` shows it), through the
// optional export plugin_describe; older loaders have no such question.
#if NCSERVO_WS_AT_LEAST(4, 4)
#include <wsutil/plugins.h>  // WS_PLUGIN_DESC_*; not installed before 4.4
#define NCSERVO_WS_DESCRIBE_PLUGIN(flags)       \
  extern "C" {                                  \
  WS_DLL_PUBLIC uint32_t plugin_describe(void); \
  }                                             \
  uint32_t plugin_describe(void) {              \
    return (flags);                             \
  }
#else
#define NCSERVO_WS_DESCRIBE_PLUGIN(flags)
#endif

namespace ncservo::ws {

// The C truth values the API takes and returns: gboolean (an int) until the given version,
// bool from then on. In C++ an int* is no bool*, so the variables must have the right type.
#if NCSERVO_WS_AT_LEAST(4, 4)
using PrefBool = bool;     // the variable of prefs_register_bool_preference
using HeurResult = bool;   // heur_dissector_t's return
using ItemBoolean = bool;  // proto_tree_add_item_ret_boolean's result
#else
using PrefBool = gboolean;
using HeurResult = gboolean;
using ItemBoolean = gboolean;
#endif
#if NCSERVO_WS_AT_LEAST(4, 2)
using UatResult = bool;  // uat_update_cb_t and uat_fld_chk_cb_t's return
#else
using UatResult = gboolean;
#endif

// The tvb accessors are tvb_get_uintN from 4.4; the tvb_get_guintN forms are deprecated there.
inline uint8_t tvbU8(tvbuff_t* tvb, int offset) {
#if NCSERVO_WS_AT_LEAST(4, 4)
  return tvb_get_uint8(tvb, offset);
#else
  return tvb_get_guint8(tvb, offset);
#endif
}

// A stats tree in a menu group: stats_tree_register_with_group until 4.2; from 4.4
// stats_tree_register returns the tree's configuration and stats_tree_set_group sets the group.
inline void registerStatsTree(const char* tap, const char* abbrev, const char* name, unsigned flags,
                              stat_tree_packet_cb packet, stat_tree_init_cb init,
                              stat_tree_cleanup_cb cleanup, register_stat_group_t group) {
#if NCSERVO_WS_AT_LEAST(4, 4)
  stats_tree_set_group(stats_tree_register(tap, abbrev, name, flags, packet, init, cleanup), group);
#else
  stats_tree_register_with_group(tap, abbrev, name, flags, packet, init, cleanup, group);
#endif
}

// A `-z` statistic's start (stat_tap_ui's init callback) returns whether it started from 4.6,
// nothing before: the plugin writes it the 4.6 way, statTapInit<start> adapts it.
template <bool (*start)(const char*, void*)>
#if NCSERVO_WS_AT_LEAST(4, 6)
bool statTapInit(const char* arguments, void* user_data) {
  return start(arguments, user_data);
}
#else
void statTapInit(const char* arguments, void* user_data) {
  start(arguments, user_data);
}
#endif

}  // namespace ncservo::ws
