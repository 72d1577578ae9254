/* Runs every C unit test and prints "N passed, N failed"; exit 1 if any failed. */
#include <stdio.h>

#define TESTS(X)                                                            \
    X(test_machine_should_follow_fig2)                                      \
    X(test_envelope_should_pass_a_command_within_the_rating)                \
    X(test_envelope_should_name_each_limit_a_command_breaks)                \
    X(test_envelope_should_stop_a_yo_turning_faster_than_its_pump)          \
    X(test_envelope_should_hold_speed_and_thrust_to_the_propulsion_s_range) \
    X(test_envelope_should_turn_a_heading_no_faster_than_the_vehicle)       \
    X(test_envelope_should_stop_a_pump_working_past_its_energy_per_hour)    \
    X(test_envelope_clamp_should_hold_values_at_the_edge_and_end_on_rates)  \
    X(test_envelope_check_should_refuse_no_envelope)                        \
    X(test_envelope_should_say_what_it_did_in_the_simulator_s_words)        \
    X(test_runtime_should_report_start_event_and_envelope_on_one_tick)      \
    X(test_runtime_should_surface_when_a_variable_takes_the_yo_past_the_rating) \
    X(test_machine_should_run_assignments_in_order)                         \
    X(test_machine_should_refuse_a_call_past_the_stack_depth)               \
    X(test_machine_should_refuse_return_with_an_empty_stack)                \
    X(test_machine_should_refuse_a_target_outside_the_table)                \
    X(test_machine_goto_should_clear_the_stack)                             \
    X(test_mission_check_should_accept_fig2_and_reject_bad_tables)          \
    X(test_yo_should_turn_at_its_depths)                                    \
    X(test_yo_should_start_climbing_below_max_and_use_planned_pitch)        \
    X(test_yo_should_turn_a_dive_at_its_altimeter_stop)                     \
    X(test_thermotrackyo_should_turn_a_dive_at_its_altimeter_stop)          \
    X(test_surface_and_hover_should_command_fixed_attitudes)                \
    X(test_cruise_and_altitude_should_fly_level_at_their_speed)             \
    X(test_a_yo_should_command_its_thrust)                                  \
    X(test_naive_tracker_should_detect_a_clean_cast)                        \
    X(test_naive_tracker_should_never_detect_a_noisy_cast)                  \
    X(test_robust_tracker_should_detect_clean_and_noisy_casts)              \
    X(test_tracker_should_turn_at_the_band_and_reset_a_lost_band)           \
    X(test_tracker_should_ignore_missing_readings)                          \
    X(test_tracker_should_keep_a_nan_band_end_on_detection)                 \
    X(test_robust_tracker_should_skip_its_walk_only_where_it_changes_nothing) \
    X(test_ddmm_should_convert_to_degrees)                                  \
    X(test_ddmm_should_equal_the_fmod_definition)                           \
    X(test_nav_should_head_to_its_point)                                    \
    X(test_noheading_and_missing_fix_should_give_no_heading)                \
    X(test_heading_should_be_held_with_or_without_a_fix_and_reach_nothing)  \
    X(test_turn_should_advance_from_the_entry_heading_at_its_rate)  \
    X(test_waypoints_should_advance_within_50_m_and_hold_the_last)          \
    X(test_goto_list_should_loop_with_its_radius_and_report_the_distance)   \
    X(test_sweep_should_mow_a_square_in_alternating_lines)                  \
    X(test_sweep_should_clip_lines_to_a_triangle)                           \
    X(test_sweep_should_stop_at_256_waypoints)                              \
    X(test_sweep_should_read_every_corner_a_route_holds)                    \
    X(test_plan_should_accept_a_good_plan)                                  \
    X(test_plan_should_read_a_yos_thrust_and_a_level_profile)               \
    X(test_plan_should_reject_bad_files_naming_the_line)                    \
    X(test_plan_should_read_a_states_power_line_where_its_mission_sleeps)   \
    X(test_plan_should_accept_computer_none_on_any_build)                   \
    X(test_plan_should_be_held_to_its_missions_bounds)                      \
    X(test_plan_should_reject_clocks_on_computer_none_and_boards_on_its_build) \
    X(test_plan_should_reject_a_file_of_only_its_checksum_line)             \
    X(test_plan_should_reject_an_overlong_line)                             \
    X(test_plan_should_reject_truncated_and_corrupted_files)                \
    X(test_plan_should_reject_a_file_over_64_kib)                           \
    X(test_plan_should_keep_the_last_good_plan_on_rejection)                \
    X(test_random_bytes_should_never_crash_the_plan_reader)                 \
    X(test_schedule_without_a_plan_should_power_every_logged_sensor)        \
    X(test_schedule_should_alternate_profiles_and_power_windows)            \
    X(test_schedule_should_give_the_remainder_to_the_last_nonzero_share)    \
    X(test_crc_should_match_catalogue_check_values)                         \
    X(test_crcs_should_equal_their_bitwise_definitions)                     \
    X(test_cobs_should_encode_the_reference_examples_in_place)              \
    X(test_command_should_travel_whole_and_as_its_changes)                  \
    X(test_command_fields_should_have_their_contract_sizes)                 \
    X(test_sensors_should_update_only_the_masked_values)                    \
    X(test_bad_frames_should_be_dropped_with_their_reason)                  \
    X(test_reader_should_resynchronise_after_garbage)                       \
    X(test_reader_should_split_one_chunk_into_its_frames)                   \
    X(test_random_bytes_should_never_crash_the_reader)                      \
    X(test_hello_should_carry_the_raw_mission_hash)                         \
    X(test_checkpoint_should_round_trip_what_is_in_use)                     \
    X(test_checkpoint_should_refuse_damaged_and_foreign_records)            \
    X(test_checkpoint_file_should_resume_from_the_newest_intact_record)     \
    X(test_checkpoint_should_survive_kill_9_at_any_point)                   \
    X(test_journal_should_give_back_its_entries_until_the_next_record)      \
    X(test_journal_should_end_at_a_torn_or_damaged_entry)                   \
    X(test_journal_should_ask_for_a_record_when_full)                       \
    X(test_checkpoint_should_refuse_an_older_format_and_another_journal_size) \
    X(test_journal_should_survive_kill_9_at_any_point)                      \
    X(test_atomic_write_should_replace_the_file_whole)                      \
    X(test_event_log_should_append_one_line_per_transition)                 \
    X(test_runtime_should_fly_fig2_and_report_each_transition)              \
    X(test_runtime_should_follow_the_plan_schedule)                         \
    X(test_runtime_should_resume_from_a_checkpoint_with_the_same_trace)     \
    X(test_runtime_should_report_start_and_event_on_tick_0_and_refuse_overflow) \
    X(test_pty_should_carry_raw_bytes_to_the_path_it_names)                 \
    X(test_pty_should_refuse_a_path_buffer_too_small)                       \
    X(test_linger_should_end_when_the_peer_hangs_up_and_else_at_its_bound)  \
    X(test_read_should_nap_briefly_on_a_line_whose_peer_hung_up)            \
    X(test_now_should_count_clock_ticks_on_a_kernel_without_a_monotonic_clock) \
    X(test_args_should_parse_every_option)                                  \
    X(test_args_should_refuse_bad_command_lines)                            \
    X(test_sha256_should_match_the_fips_180_examples)                       \
    X(test_hmac_sha256_should_match_rfc_4231)                               \
    X(test_tags_should_compare_every_byte)                                  \
    X(test_signed_plan_should_carry_the_tag_gliderplan_plan_sign_writes)    \
    X(test_update_should_make_its_change_and_sign_the_result)               \
    X(test_update_should_refuse_forged_stale_and_replayed_updates_and_other_plans) \
    X(test_update_should_refuse_malformed_updates_naming_the_change)        \
    X(test_update_should_refuse_a_plan_the_reader_refuses)                  \
    X(test_update_should_set_a_thrusters_power_within_its_rating)           \
    X(test_update_decimal_text_should_write_plan_numbers)                   \
    X(test_random_updates_should_never_crash_the_applier)                   \
    X(test_signed_plan_should_refuse_unsigned_tampered_replayed_and_foreign_plans) \
    X(test_signed_plan_should_have_a_well_formed_tail)                      \
    X(test_key_file_should_be_64_hex_digits_readable_by_its_owner_only)    \
    X(test_energy_guard_should_end_the_mission_in_any_state_and_stack_depth)

#define DECLARE(name) void name(void);
TESTS(DECLARE)

static int failures;
static const char *current;

void gp_test_fail(const char *file, int line, const char *what)
{
    failures++;
    printf("FAIL %s: %s:%d: %s\n", current, file, line, what);
}

int main(void)
{
    int passed = 0, failed = 0;
#define RUN(name)                     \
    {                                 \
        int before = failures;        \
        current = #name;              \
        name();                       \
        if (failures == before) {     \
            passed++;                 \
        } else {                      \
            failed++;                 \
        }                             \
    }
    TESTS(RUN)
    printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
