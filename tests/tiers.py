"""
The suite's two tiers. ``make test`` runs the quick one, within 2.5 minutes on two cores with an
empty kernel cache (``sh tools/time-suite.sh`` measures it as CI and a new user see it): the
plugin matrix (every plugin, variant and texture kind), every plugin against its float64
reference, its sampler's χ² and its energy, every check against a deliberately broken BSDF
(the gradients of lambert and cooktorrance), every command's options and errors, and each case
below at its first parameters. ``make test-slow`` runs the tests listed here, marked ``slow``;
``make test-full`` runs both tiers, and CI runs both.

Each entry is a test function of a file, all of it (a reason alone) or the listed parameter
ids of it (a reason and the ids; an id ending in ``*`` stands for those that start so). The
reasons say what the quick tier keeps of it. ``conftest.py`` marks them, and refuses an entry
that names no collected test, so the list stays true as tests are renamed.
"""

#: A command's whole run at its quick size: the quick tier tests the parts it is made of, its
#: options and its errors, and the command once more through another test of the same file.
WHOLE = "whole run"

#: The same assertion at more parameters, variants or plugins: the quick tier keeps the
#: test's first case (the llvm_ad_rgb one where it runs in scalar_rgb and llvm_ad_rgb).
MORE = "more cases"

#: A deeper sweep of one plugin or check (stability over a range, a render or a traverse update
#: against the built-in twin, a second broken-on-purpose case of a defect already rejected)
#: beside what the quick tier asserts of it: eval, χ², furnace, matrix, gradients.
DEEP = "deeper sweep"

SLOW = {
    "tests/audit/test_audit.py": {
        "test04_quick_audit_as_a_user_runs_it": WHOLE,
        "test06_each_reproducer_exits_1_while_the_defect_is_present": (MORE, [
            "repro_blendbsdf_sampled_component", "repro_mask_context",
            "repro_pplastic_components", "repro_principled_component_slots",
            "repro_principled_context", "repro_principled_lobes_growth",
            "repro_principledthin_pdf_mask", "repro_roughplastic_gradients",
            "repro_roughplastic_pdf_mask", "repro_twosided_back_component",
            "repro_twosided_back_selection"]),
    },
    "tests/campaign/test_campaign.py": {
        "test01_quick_campaign": WHOLE,
        "test02_quick_benchmark": WHOLE,
    },
    "tests/campaign/test_earth_section.py": {
        "test01_quick_section_rows": WHOLE,
    },
    "tests/campaign/test_hk_section.py": {
        "test01_quick_section_rows": WHOLE,
        "test02_without_the_n2_law_the_comparison_fails": DEEP,
    },
    "tests/campaign/test_multiscatter_section.py": {
        "test01_quick_section_rows_values_and_figures": WHOLE,
        "test03_dielectric_tables_scaled_by_098_fail_the_furnace": DEEP,
    },
    "tests/campaign/test_validation_scripts.py": {
        "test01_bench_render_quick": WHOLE,
        "test02_phong_float32_quick": WHOLE,
        "test03_profile_kernels_quick": WHOLE,
        "test04_merl_layout_quick": WHOLE,
    },
    "tests/checks/test_batch.py": {
        "test03_evaluate_is_lambert": (MORE, ["llvm_ad_rgb"]),
        "test04_sample_is_lambert": (MORE, ["llvm_ad_rgb"]),
        "test05_a_wrong_value_is_seen": (MORE, ["llvm_ad_rgb"]),
    },
    "tests/checks/test_checks.py": {
        "test05_consistency_accepts": (MORE, ["scalar_rgb"]),
        "test06_consistency_rejects": (MORE, [
            "scalar_rgb-weight-weight vs eval/pdf", "scalar_rgb-bspdf-bs.pdf vs pdf(bs.wo)",
            "llvm_ad_rgb-bspdf-bs.pdf vs pdf(bs.wo)"]),
        "test08_energy_rejects_energy_gain": (MORE, ["scalar_rgb"]),
        "test12_reciprocity_and_positivity_accept": (MORE, ["scalar_rgb"]),
        "test13_reciprocity_rejects_one_sided_dependence": (MORE, ["llvm_ad_rgb"]),
        "test14_positivity_rejects": (MORE, ["llvm_ad_rgb-negative", "llvm_ad_rgb-nan"]),
        "test15_stability_accepts": (MORE, ["scalar_rgb"]),
        "test16_stability_rejects_nan_at_grazing": (MORE, ["llvm_ad_rgb"]),
        "test18_furnace_accepts": (MORE, ["roughconductor"]),
        "test19_furnace_rejects": (MORE, ["weight"]),
        "test23_battery_on_builtin": DEEP,
        "test25_pytest_helpers_raise_with_the_message": (MORE, ["scalar_rgb"]),
    },
    "tests/checks/test_gradients.py": {
        "test01_a_broken_derivative_is_found": (MORE, [
            "eval_detached", "eval_sign", "weight_sign"]),
        "test02_every_plugin_passes": (MORE, [
            "phong", "ward", "orennayar", "ashikhmin", "lafortune", "merl-*", "he", "rtls",
            "rpv", "ocean", "hapke", "hk", "phong-original-halfway",
            "cooktorrance-0.3-smith-ggx-0.6",
            "cooktorrance-True-0.5-Au", "cooktorrance-True-0.5", "cooktorrance-True-True-0.45",
            "orennayar-full", "ashikhmin-10.0-200.0", "ward-0.1-0.3",
            "lafortune-20.0-1.0-1.0-1.0", "hk-all-1.3-0.4-0.6-1.5"]),
        "test03_the_compensated_glass_carries_eta_into_its_tables": DEEP,
    },
    "tests/checks/test_lobes.py": {
        "test01_lobe_checks_accept": (MORE, ["roughdielectric", "plastic"]),
    },
    "tests/cli/test_cli.py": {
        "test01_render_smoke": (MORE, ["scalar_rgb"]),
        "test02_default_scene_is_the_showcase": WHOLE,
        "test04_ctrl_c_keeps_what_is_done": (MORE, ["SIGTERM"]),
    },
    "tests/cli/test_cli_checks.py": {
        "test02b_the_json_is_strict": DEEP,
        "test04_furnace_table_and_render": WHOLE,
        "test05_plots": (MORE, ["albedo", "slice"]),
    },
    "tests/cli/test_cli_modes.py": {
        "test01_an_option_the_mode_does_not_take_is_refused": (MORE, [
            "fit a.binary b.binary --model ward"]),
    },
    "tests/cli/test_cli_outputs.py": {
        "test01_an_existing_file_is_refused_untouched": (MORE, [
            "fit gold.binary --models ward (gold-models/models.md)",
            "fit gold.binary --models ward --out mine (mine/spheres.png)",
            "fit a.binary b.binary --models ward (sweep/sweep.json)",
            "validate --quick (validation/REPORT.md)",
            "bench --quick --out b (b/SPEED_ACCURACY.md)"]),
    },
    "tests/measured/test_format.py": {
        "test05_bad_files_are_one_line": (MORE, [
            "nan-1 values are NaN or beyond float32's range",
            "huge-1 values are NaN or beyond float32's range"]),
        "test08_cli": WHOLE,
        "test11_what_no_table_holds_is_refused_before_writing": (MORE, [
            "diffuse reflectance=0-is 0 at every bin above the horizon",
            "roughdielectric specular_reflectance=0-is 0 at every bin above the horizon"]),
    },
    "tests/plugins/test_argument_forms.py": {
        "test01_directions_as_lists_and_tuples": (MORE, [
            "llvm_ad_rgb-lambert", "llvm_ad_rgb-phong", "llvm_ad_rgb-cooktorrance",
            "llvm_ad_rgb-ward"]),
        "test03_inside_twosided": (MORE, [
            "llvm_ad_rgb-lambert", "llvm_ad_rgb-cooktorrance",
            "llvm_ad_rgb-cooktorrance-anisotropic"]),
        "test04_inside_blendbsdf": (MORE, [
            "llvm_ad_rgb-lambert", "llvm_ad_rgb-cooktorrance",
            "llvm_ad_rgb-cooktorrance-anisotropic", "llvm_ad_rgb-cooktorrance-transmission"]),
        "test05_inside_normalmap": (MORE, [
            "llvm_ad_rgb-lambert", "llvm_ad_rgb-cooktorrance",
            "llvm_ad_rgb-cooktorrance-anisotropic", "llvm_ad_rgb-cooktorrance-transmission"]),
    },
    "tests/plugins/test_ashikhmin.py": {
        "test04_eval_pdf_against_reference": (MORE, ["llvm_ad_spectral", "llvm_ad_rgb"]),
        "test07_chi2": (MORE, ["(10.0, 1000.0)-45deg", "(30.0, 3.0)-85deg"]),
        "test09_stability": DEEP,
        "test10_textures_and_render": DEEP,
    },
    "tests/plugins/test_at_bounds.py": {
        "test02_finite_at_the_bounds_in_scalar_rgb": (MORE, ["he", "merl"]),
    },
    "tests/plugins/test_cooktorrance.py": {
        "test01_create_and_defaults": (MORE, ["llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test02_diffuse_base_is_a_second_lobe": (MORE, ["llvm_ad_rgb"]),
        "test04_eval_equals_the_float64_reference": (MORE, [
            "llvm_ad_rgb-textbook", "llvm_ad_rgb-ggx-smith-schlick",
            "llvm_ad_rgb-rgb-conductor-diffuse", "llvm_ad_rgb-no-fresnel-rough"]),
        "test05_smith_equals_roughconductor": (MORE, [
            "llvm_ad_rgb-beckmann-visible-Au", "llvm_ad_rgb-beckmann-all-normals-eta-k",
            "llvm_ad_rgb-ggx-visible-eta-k", "llvm_ad_rgb-ggx-all-normals-Au",
            "llvm_ad_spectral-beckmann-visible-Au",
            "llvm_ad_spectral-beckmann-all-normals-eta-k",
            "llvm_ad_spectral-ggx-visible-eta-k", "llvm_ad_spectral-ggx-all-normals-Au",
            "llvm_ad_mono-beckmann-visible-Au", "llvm_ad_mono-ggx-visible-eta-k"]),
        "test06_samples_equal_roughconductors": DEEP,
        "test07_k0_equals_roughdielectric_reflection": (MORE, [
            "llvm_ad_rgb-beckmann", "llvm_ad_rgb-ggx"]),
        "test08_smooth_limit_is_the_fresnel_reflectance": (MORE, ["all-normals"]),
        "test09_chi2": (MORE, [
            "beckmann-vcavity-vis-a0.02-cos1.0", "beckmann-vcavity-all-a1.0-cos0.1",
            "ggx-smith-vis-a0.1-cos1.0", "ggx-vcavity-vis-a0.5-cos0.1",
            "ggx-vcavity-all-a0.1-cos1.0"]),
        "test13_weight_is_eval_over_pdf": (MORE, [
            "scalar_rgb-diffuse", "scalar_rgb-smooth", "llvm_ad_rgb-default",
            "llvm_ad_rgb-diffuse", "llvm_ad_rgb-ggx-smith-schlick-all", "llvm_ad_rgb-smooth",
            "llvm_ad_rgb-smooth-alone", "llvm_ad_rgb-smith-ggx-rough",
            "llvm_ad_rgb-vcavity-dcos"]),
        "test14_white_furnace": (MORE, [
            "beckmann-vcavity-all-a0.5", "ggx-smith-all-a0.5", "ggx-vcavity-vis-a0.02"]),
        "test15_smith_beckmann_samples_like_roughconductor": DEEP,
        "test17_furnace_render": DEEP,
        "test18_stability": DEEP,
        "test20_named_conductors_are_roughconductors": (MORE, [
            "llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test21_conductor_ior_is_the_materials": (MORE, ["scalar_rgb"]),
        "test22_render_equals_roughconductor": DEEP,
        "test23_render_other_variants": DEEP,
        "test24_traverse_update_and_gradient": DEEP,
        "test25_reciprocity_and_positivity": (MORE, ["scalar_rgb"]),
        "test27_mixture_pdf_against_the_reference": (MORE, [
            "scalar_rgb-textbook", "llvm_ad_rgb-rgb-conductor-diffuse", "llvm_ad_rgb-textbook"]),
    },
    "tests/plugins/test_cooktorrance_anisotropic.py": {
        "test01_smith_equals_anisotropic_roughconductor": (MORE, [
            "llvm_ad_rgb-beckmann-visible-u<v", "llvm_ad_rgb-beckmann-all-normals-u>v",
            "llvm_ad_rgb-ggx-visible-u>v", "llvm_ad_rgb-ggx-all-normals-u<v",
            "llvm_ad_spectral-beckmann-visible-u<v",
            "llvm_ad_spectral-beckmann-all-normals-u>v", "llvm_ad_spectral-ggx-visible-u>v",
            "llvm_ad_spectral-ggx-all-normals-u<v", "llvm_ad_mono-beckmann-visible-u<v",
            "llvm_ad_mono-ggx-visible-u>v"]),
        "test02_samples_equal_roughconductors": DEEP,
        "test03_eval_equals_the_float64_reference": (MORE, [
            "llvm_ad_rgb-vcavity-beckmann", "llvm_ad_rgb-smith-ggx-diffuse"]),
        "test04_chi2": (MORE, [
            "beckmann-vcavity-vis-0.04:0.4-0deg", "beckmann-vcavity-all-0.04:0.4-0deg",
            "ggx-smith-vis-0.4:0.04-45deg", "ggx-vcavity-all-0.4:0.04-45deg",
            "ggx-vcavity-vis-0.04:0.4-85deg"]),
        "test13_chi2_upstream_cases": DEEP,
        "test06_white_furnace": (MORE, ["smith"]),
        "test07_brushed_render_equals_roughconductor": DEEP,
        "test08_flags_traverse_and_gradient": DEEP,
        "test10_stability": DEEP,
    },
    "tests/explore/test_page.py": {
        "test04_two_pages_keep_their_own_state": DEEP,  # (the browser test: two windows)
        "test05_the_server_serves_and_stops_on_sigterm": WHOLE,
        "test07_the_fit_button_fits_the_second_bsdf": WHOLE,
    },
    "tests/explore/test_sphere.py": {
        "test04_other_lights_light_the_side_towards_them": (MORE, ["point", "envmap"]),
        "test07_a_scene_file_with_the_bsdf_swapped": DEEP,  # (test_page: the notebook's scene)
    },
    "tests/plugins/test_opaque_parameters.py": {
        "test01_a_second_change_reuses_the_first_ones_kernels": (MORE, [
            "orennayar-sigma.color1.value", "he-tau", "rtls-f_vol.value", "rtls-f_geo.value",
            "rtls-f_iso.color0.value", "rpv-g.value", "hapke-b.value", "hapke-h.value"]),
    },
    "tests/plugins/test_cooktorrance_film.py": {
        "test06_compensated_white_furnace_with_a_film": DEEP,
        "test07_gradient_through_the_thickness": DEEP,
        "test08_rgb_gradient_through_the_film_index": DEEP,
        "test10_compensated_dielectric_white_furnace_with_a_film": (MORE, [
            "llvm_ad_rgb-60.0", "llvm_ad_rgb-180.0", "llvm_ad_rgb-120.0",
            "llvm_ad_spectral-*"]),
        "test12_compensated_dielectric_with_a_film_is_reciprocal": DEEP,
        "test11_compensated_dielectric_with_a_film_samples_its_pdf": DEEP,
        "test13_compensated_dielectric_gradients": DEEP,
        "test14_compensated_dielectric_with_a_film_in_every_variant": (MORE, [
            "llvm_ad_rgb", "scalar_spectral", "llvm_ad_spectral", "llvm_ad_mono"]),
    },
    "tests/plugins/test_cooktorrance_multiscatter.py": {
        "test01_a_table_slice_rebuilds": (MORE, ["beckmann-vcavity-40"]),
        "test02_table_interpolation_matches_numpy": (MORE, ["llvm_ad_rgb"]),
        "test03b_a_textured_roughness_takes_the_2d_lookup": (MORE, ["llvm_ad_rgb"]),
        "test03_eval_equals_the_float64_reference": (MORE, [
            "scalar_rgb-white-ggx-smith", "scalar_rgb-gold-exact",
            "llvm_ad_rgb-white-beckmann-vcavity", "llvm_ad_rgb-gold-exact",
            "llvm_ad_rgb-schlick-diffuse", "llvm_ad_rgb-anisotropic"]),
        "test05_white_furnace_reads_one": (MORE, [
            "beckmann-smith-0.6-False", "ggx-vcavity-0.3-True"]),
        "test08_chi2": (MORE, ["beckmann-vcavity-45", "gold-diffuse-85"]),
        "test10_consistency_and_reciprocity": (MORE, ["schlick-diffuse", "anisotropic"]),
        "test13_every_variant_loads_evaluates_and_samples": (MORE, [
            "llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
    },
    "tests/plugins/test_cooktorrance_multiscatter_dielectric.py": {
        "test03_eval_equals_the_float64_reference": (MORE, [
            "scalar_rgb-ggx", "scalar_rgb-beckmann-water-tinted",
            "llvm_ad_rgb-beckmann-water-tinted"]),
        "test04_white_furnace_reads_one_from_both_sides": (MORE, [
            "ggx-0.3-120.0", "ggx-1.0-175.0", "beckmann-1.0-45.0", "beckmann-0.6-150.0"]),
        "test07_chi2": (MORE, ["ggx-45", "beckmann-85"]),
        "test09_consistency_and_components": (MORE, ["TransportMode.Importance"]),
        "test10_furnace_render": DEEP,
        "test11_every_variant_loads_evaluates_and_samples": (MORE, [
            "llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
    },
    "tests/plugins/test_cooktorrance_polarized.py": {
        "test01_eval_equals_roughconductors_mueller_matrix": (MORE, [
            "llvm_ad_spectral_polarized-gold", "llvm_ad_spectral_polarized-ggx-eta-k",
            "llvm_ad_spectral_polarized-anisotropic-copper"]),
        "test02_samples_equal_roughconductors": DEEP,
        "test03_unpolarized_fresnel_terms_are_depolarizers": (MORE, [
            "llvm_ad_spectral_polarized-none", "llvm_ad_spectral_polarized-multiscatter-none"]),
        "test04_compensation_and_diffuse_base_add_depolarized": DEEP,
        "test05_polarized_render_equals_roughconductors": DEEP,
    },
    "tests/plugins/test_cooktorrance_transmission.py": {
        "test01_equals_roughdielectric": (MORE, [
            "llvm_ad_rgb-iso-beckmann-visible", "llvm_ad_rgb-aniso-beckmann-all-normals",
            "llvm_ad_rgb-aniso-ggx-visible", "llvm_ad_rgb-iso-ggx-all-normals",
            "llvm_ad_spectral-iso-beckmann-visible",
            "llvm_ad_spectral-aniso-beckmann-all-normals",
            "llvm_ad_spectral-aniso-ggx-visible", "llvm_ad_spectral-iso-ggx-all-normals",
            "llvm_ad_mono-iso-beckmann-visible", "llvm_ad_mono-aniso-beckmann-all-normals",
            "llvm_ad_mono-aniso-ggx-visible", "llvm_ad_mono-iso-ggx-all-normals"]),
        "test02_samples_equal_roughdielectrics": DEEP,
        "test04_eval_equals_the_float64_reference": (MORE, [
            "llvm_ad_rgb-beckmann", "llvm_ad_rgb-ggx-aniso-water"]),
        "test05_smooth_limit_is_dielectric": DEEP,
        "test06_energy_and_the_reference_albedo": (MORE, ["ggx"]),
        "test10_chi2_upstream_cases": (MORE, [
            "ggx-visible-grazing", "from-inside-tir", "from-inside-all-normals",
            "from-the-denser-side", "reflection-lobe-aniso", "transmission-lobe-aniso"]),
        "test13_glass_render_equals_roughdielectric": DEEP,
        "test14_traverse_update_and_gradient_through_prb": DEEP,
        "test15_render_other_variants": DEEP,
        "test16_flags_and_components_are_roughdielectrics": (MORE, ["llvm_ad_rgb"]),
        "test17_stability": DEEP,
    },
    "tests/plugins/test_he_plugin.py": {
        "test01_create": (MORE, [
            "scalar_rgb", "scalar_spectral", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test03_eval_is_the_reference": (MORE, [
            "westin-intermediate", "westin-rough", "holzschuch-smooth",
            "holzschuch-intermediate", "holzschuch-rough"]),
        "test04_spectral_variants_evaluate_at_the_sampled_wavelengths": DEEP,
        "test06_the_smooth_limit": DEEP,
        "test07_sampling_matches_pdf": DEEP,  # he's χ² (kernels of 6 s); warp's in test_merl
        "test08_consistent_reciprocal_and_efficient": DEEP,
        "test09_sigma0_through_traverse": DEEP,
        "test11_stable_from_smooth_to_rough": DEEP,
        "test12_a_smooth_surface_in_scalar_variants": (MORE, ["scalar_spectral"]),
        "test13_sigma0_and_tau_out_of_range_through_traverse": DEEP,
        "test14_a_render_with_both_below_range_and_gradients_inside": DEEP,
        "test16_the_centred_window_in_float32_to_he_s_bounds": (MORE, ["llvm_ad_rgb-20.0"]),
    },
    "tests/plugins/test_lafortune.py": {
        "test03_mirror_lobe_is_phong": DEEP,
        "test04_chi2_three_lobes": (MORE, ["60.0", "85.0"]),
        "test09_stability": DEEP,
        "test10_textures_and_render": DEEP,
    },
    "tests/plugins/test_lambert.py": {
        "test01_create": (MORE, ["llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test02_eval_pdf_closed_form": (MORE, ["llvm_ad_rgb"]),
        "test03_equals_diffuse_pointwise": (MORE, [
            "llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test04_sample_weight_and_pdf_consistency": (MORE, ["llvm_ad_rgb"]),
        "test06_white_furnace_render": (MORE, ["scalar_rgb"]),
        "test07_render_equals_diffuse": DEEP,
        "test08_xml_textures_and_nesting": DEEP,
        "test09_traverse_update_and_gradient": DEEP,
        "test10_bad_reflectance": (MORE, ["llvm_ad_rgb-above1"]),
    },
    "tests/plugins/test_matrix.py": {
        "test02_every_plugin_with_every_texture_kind": (MORE, [
            "llvm_ad_mono", "llvm_ad_spectral", "llvm_ad_spectral_polarized"]),
    },
    "tests/plugins/test_merl.py": {
        "test01_create": (MORE, [
            "llvm_ad_rgb", "scalar_spectral", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test04_eval_is_the_interpolated_table": (MORE, ["scalar_rgb"]),
        "test04b_eval_of_random_data": DEEP,
        "test06_nearest_is_merl_lookup": (MORE, ["scalar_rgb"]),
        "test07_colours_in_every_variant": (MORE, [
            "scalar_rgb", "scalar_spectral", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test08_sampling_matches_pdf": (MORE, ["45.0", "80.0"]),
        "test10_consistent_and_efficient": DEEP,
        "test12_one_load_per_file": DEEP,
    },
    "tests/plugins/test_hk.py": {
        "test04_sampler_matches_its_pdf_under_glass": DEEP,
    },
    # the quick tier keeps the layer under glass of g = 0.6 (its tables built once) and the
    # isotropic one
    "tests/plugins/test_hk_all.py": {
        "test01_bands_equal_the_random_walk": (MORE, ["1"]),
        "test04_each_channel_is_its_own_grey_layer": (MORE, ["True"]),
    },
    "tests/plugins/test_ocean.py": {
        "test06_finite_and_non_negative_at_the_singular_places": (MORE, ["llvm_ad_rgb"]),
        "test09_polarized_variants": (MORE, ["llvm_ad_spectral_polarized"]),
        "test12_visible_normal_sampling": DEEP,
        "test13_reciprocal": DEEP,
        "test14_without_shadowing_the_albedo_exceeds_1": DEEP,
    },
    "tests/plugins/test_orennayar.py": {
        "test01_create": (MORE, ["llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test02_eval_against_reference": (MORE, ["llvm_ad_rgb-qualitative", "llvm_ad_rgb-full"]),
        "test03_sigma_zero_is_lambert_bit_for_bit": DEEP,
        "test04_albedo_at_normal_incidence_closed_form": (MORE, ["full"]),
        "test05_albedo_curve_and_energy": (MORE, ["full-pi_2"]),
        "test06_reciprocity_and_consistency": (MORE, [
            "scalar_rgb-qualitative", "scalar_rgb-full", "llvm_ad_rgb-full"]),
        "test08_backscatter_grows_with_roughness": (MORE, ["llvm_ad_rgb"]),
        "test15_full_form_clamped_where_the_paper_is_negative": (MORE, ["llvm_ad_rgb"]),
        "test09_stability": DEEP,
        "test10_renders_in_every_variant": DEEP,
        "test11_textures": (MORE, ["scalar_rgb"]),
    },
    "tests/plugins/test_parameters.py": {
        "test05_material_none_is_a_perfect_conductor": (MORE, ["scalar_rgb"]),
        "test06_a_misspelt_parameter_names_the_closest": (MORE, [
            "scalar_rgb-he", "llvm_ad_rgb-lambert", "llvm_ad_rgb-cooktorrance",
            "llvm_ad_rgb-he"]),
    },
    "tests/plugins/test_phong.py": {
        "test01_create": (MORE, ["llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test02_eval_pdf_against_reference": (MORE, ["scalar_rgb"]),
        "test03_light_side_in_both_transport_modes": (MORE, ["llvm_ad_rgb"]),
        "test04_sample_weight_and_pdf_consistency": (MORE, [
            "scalar_rgb-normalized-mirror", "scalar_rgb-lecture-halfway",
            "scalar_rgb-original-mirror", "scalar_rgb-original-halfway",
            "llvm_ad_rgb-lecture-halfway", "llvm_ad_rgb-original-mirror",
            "llvm_ad_rgb-original-halfway"]),
        "test05_chi2": (MORE, [
            "normalized-halfway-n100-0deg", "lecture-mirror-n10-45deg",
            "lecture-halfway-n1000-84.26deg", "original-mirror-n100-84.26deg",
            "original-halfway-n1-0deg"]),
        "test06_chi2_each_lobe_alone": (MORE, [
            "mirror-c1-n1000-37deg", "halfway-c0-n1000-37deg", "halfway-c1-n10-grazing"]),
        "test07_albedo_at_normal_incidence_equals_closed_form": (MORE, [
            "normalized-halfway", "lecture-mirror", "lecture-halfway", "original-mirror",
            "original-halfway"]),
        "test08_albedo_curve_matches_float64_quadrature": (MORE, [
            "lecture-halfway-10000.0", "original-halfway-10.0", "original-mirror-10000.0"]),
        "test09_reciprocity": (MORE, [
            "scalar_rgb-mirror", "scalar_rgb-halfway", "llvm_ad_rgb-halfway"]),
        "test10_white_furnace_energy": (MORE, [
            "normalized-halfway-n1000", "lecture-mirror-n10", "lecture-halfway-n10",
            "original-halfway-n10"]),
        "test11_white_furnace_render": (MORE, ["lecture", "original"]),
        "test12_stability": DEEP,
        "test13_original_form_light_at_the_horizon": (MORE, ["llvm_ad_rgb"]),
        "test14_float32_eval_follows_float64": (MORE, ["halfway"]),
        "test16_renders_in_every_variant": DEEP,
        "test17_textures": DEEP,
        "test18_lobes_left_out": (MORE, ["llvm_ad_rgb"]),
        "test19_traverse_update_and_gradients": DEEP,
        "test20_exponent_gradient_of_eval": (MORE, ["halfway"]),
        "test22_bad_input": (MORE, ["llvm_ad_rgb-exponent0"]),
    },
    "tests/plugins/test_plugin_shape.py": {
        "test01_every_plugin_is_a_mixture_of_declared_lobes": (MORE, ["llvm_ad_rgb-lambert"]),
    },
    "tests/plugins/test_registration.py": {
        "test01_loadable_in_every_variant": (MORE, [
            "llvm_ad_rgb", "scalar_spectral", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test02_loadable_from_xml": (MORE, ["llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test03_register_is_idempotent": (MORE, ["llvm_ad_rgb"]),
        "test04_no_builtin_is_shadowed": (MORE, ["llvm_ad_rgb"]),
    },
    "tests/plugins/test_hapke.py": {
        "test05_eval_is_the_reference": (MORE, ["llvm_ad_rgb"]),
        "test09_reciprocal_and_consistent": DEEP,
        "test10_opposition_sampling": DEEP,
        "test11_parameters_through_traverse": DEEP,
    },
    "tests/plugins/test_rpv.py": {
        "test03_eval_is_the_reference": (MORE, ["scalar_rgb"]),
        "test07_reciprocal_and_consistent": DEEP,
        "test08_hot_spot_sampling": DEEP,
    },
    "tests/plugins/test_rtls_modis.py": {
        "test05_the_fit_recovers_an_rtls_targets_weights": DEEP,
        "test06_the_fit_to_another_bsdf_is_the_linear_inversion": (MORE, ["roughplastic"]),
    },
    "tests/plugins/test_textures.py": {
        "test01_procedural_texture_out_of_range_is_rejected": (MORE, [
            "llvm_ad_rgb-lambert-reflectance-0"]),
        "test02_procedural_texture_in_range_is_kept": (MORE, ["llvm_ad_rgb"]),
        "test03_unknowable_texture_is_clamped_at_evaluation": (MORE, ["llvm_ad_rgb"]),
        "test04_clamped_eta_gives_a_valid_cooktorrance": (MORE, ["llvm_ad_rgb"]),
        "test05_a_mesh_attribute_weighs_the_lobes_where_it_is_evaluated": (MORE, [
            "llvm_ad_rgb-phong-diffuse_reflectance", "llvm_ad_rgb-ward-specular_reflectance",
            "llvm_ad_rgb-ashikhmin-diffuse_reflectance",
            "llvm_ad_rgb-lafortune-specular_reflectance_0",
            "llvm_ad_rgb-cooktorrance-diffuse_reflectance"]),
        "test06_spectral_variants_take_a_bitmap_reflectance": (MORE, ["llvm_ad_spectral"]),
        "test07_values_set_through_traverse_are_clipped": (MORE, ["spec4-eta--1.0"]),
    },
    "tests/plugins/test_ward.py": {
        "test01_create": (MORE, ["llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
        "test02_eval_pdf_against_reference": (MORE, [
            "llvm_ad_rgb-original", "llvm_ad_rgb-duer", "llvm_ad_rgb-balanced"]),
        "test03_sampler_is_wards_recipe": (MORE, ["llvm_ad_rgb"]),
        "test04_sample_weight_and_pdf_consistency": (MORE, [
            "scalar_rgb-original", "scalar_rgb-duer", "scalar_rgb-balanced",
            "llvm_ad_rgb-duer", "llvm_ad_rgb-balanced"]),
        "test05_chi2": (MORE, ["(0.5, 0.05)-85deg"]),
        "test08_albedo_and_energy_of_each_form": (MORE, ["duer-1.0", "original-0.5"]),
        "test10_reciprocity": (MORE, [
            "scalar_rgb-original", "scalar_rgb-duer", "scalar_rgb-balanced",
            "llvm_ad_rgb-duer", "llvm_ad_rgb-balanced"]),
        "test12_stability": DEEP,
        "test13_renders_in_every_variant": DEEP,
        "test14_textures": DEEP,
    },
    "tests/reference/test_he.py": {
        "test04_reciprocity": (MORE, ["paper-g>>1"]),
        "test06_every_regime_is_finite_and_non_negative": (MORE, ["g>>1"]),
        "test07_series_converges_and_its_tail_bound_holds": (MORE, ["5000.0-0.0"]),
        "test07b_terms_beyond_float64_are_skipped": (MORE, [
            "18.0-3000000000.0", "0.5-10000000.0"]),
        "test13_directional_albedo_as_measured": (MORE, [
            "near-perfect conductor, \\u03b1 = 0.4-westin-75",
            "bbm's default roughness, metal-westin-0",
            "bbm's default roughness, metal-paper-0",
            "bbm's default roughness, metal-holzschuch-0", "Westin's test surface-westin-0",
            "Westin's test surface-paper-0", "rough glass + a = 0.2-westin-0"]),
        "test14_disk_rule_against_the_hemisphere_grid": DEEP,
    },
    "tests/reference/test_hk_doubling.py": {
        "test01_equal_to_the_random_walk": (MORE, [
            "0.0-1.0-False", "0.0-1.5-False", "0.0-1.5-True", "0.7-1.0-False", "0.7-1.0-True",
            "0.7-1.5-True"]),
        "test02_energy_is_conserved_at_albedo_one": (MORE, [
            "0.7-1.0-1e-06", "0.0-1.5-1e-06", "0.9-1.5-1e-05"]),
    },
    "tests/reference/test_hk_reference.py": {
        "test04_single_term_and_beam_equal_the_walk": (MORE, ["1", "2", "3"]),
        "test05_single_lobe_in_bins_equals_the_walk": DEEP,
    },
    "tests/reference/test_phong_reference.py": {
        "test03_albedo_curve_equals_brute_force_quadrature": (MORE, [
            "normalized-halfway", "lecture-mirror", "lecture-halfway", "original-mirror",
            "original-halfway"]),
    },
    "tests/reference/test_randomwalk.py": {
        "test01_white_furnace_conductor": (MORE, ["ggx"]),
        "test02_order_one_is_height_correlated_smith": (MORE, [
            "beckmann-0.5-85.0-0.0", "beckmann-1.0-0.0-0.0", "beckmann-alpha5-70.0-0.4"]),
        "test03_multiple_scattering_is_reciprocal": (MORE, ["beckmann-0.8-a1-b1"]),
        "test05_dielectric_conserves_energy": (MORE, ["ggx"]),
        "test06_dielectric_order_one": (MORE, ["beckmann-75.0", "ggx-140.0", "beckmann-120.0"]),
    },
    "tests/reference/test_ward_reference.py": {
        "test01_ward_albedo_at_normal_incidence": (MORE, ["duer", "balanced"]),
        "test03_ward_albedo_against_brute_force": (MORE, ["duer", "balanced"]),
    },
    "tests/scattering/test_ashikhmin_terms.py": {
        "test02_half_vector_sampler_has_the_papers_density": (MORE, ["3.0-60.0", "60.0-3.0"]),
    },
    "tests/scattering/test_fresnel.py": {
        "test02_fresnel_per_channel_and_schlick": (MORE, [
            "llvm_ad_rgb", "llvm_ad_spectral", "llvm_ad_mono"]),
    },
    "tests/scattering/test_he_terms.py": {
        "test01_terms_match_the_reference": (MORE, [
            "s0.02-t1.0-holzschuch", "s0.18-t3.0-westin", "s0.18-t3.0-holzschuch",
            "s0.5-t2.0-westin", "s0.5-t2.0-holzschuch", "s1.0-t4.0-westin",
            "s1.0-t4.0-holzschuch"]),
        "test02_the_paper_reading_and_where_its_window_stops": DEEP,
    },
    "tests/scattering/test_hk_orders.py": {
        "test01_tables_within_their_promise": (MORE, [
            "grid-0", "grid-1", "grid-2", "grid-3", "constant-1", "constant-2",
            "constant-3"]),
        "test02_a_constant_medium_is_the_grid_interpolated_once": (MORE, ["3"]),
    },
    "tests/scattering/test_lafortune_lobes.py": {
        "test02_sampler_matches_its_density": (MORE, ["78deg", "87deg"]),
    },
    "tests/scattering/test_microfacet_anisotropic.py": {
        "test01_d_and_g1_are_mitsubas": (MORE, ["pair1-beckmann", "pair1-ggx", "pair2-beckmann"]),
        "test02_terms_match_the_float64_reference": (MORE, ["ggx"]),
        "test04_ndf_normalised_and_weak_white_furnace": (MORE, ["ggx-pair1"]),
        "test06_normal_samplers_match_their_densities": (MORE, [
            "0.0-pair0-ggx", "0.0-pair1-beckmann", "0.0-pair1-ggx",
            "0.7853981633974483-pair0-beckmann", "0.7853981633974483-pair0-ggx",
            "0.7853981633974483-pair1-beckmann", "0.7853981633974483-pair1-ggx",
            "1.45-pair0-beckmann", "1.45-pair1-beckmann"]),
    },
    "tests/scattering/test_microfacet_terms.py": {
        "test01_d_and_g1_are_mitsubas": (MORE, ["0.0001-ggx", "0.02-beckmann", "0.02-ggx"]),
        "test05_ndf_normalised_and_weak_white_furnace": (MORE, [
            "ggx-0.1", "ggx-0.5", "beckmann-1.0"]),
        "test07_normal_samplers_match_their_densities": (MORE, [
            "0.1-ggx", "0.5-beckmann", "0.5-ggx"]),
        "test08_vcavity_visible_normals": (MORE, [
            "0.3-ggx", "1.2-beckmann", "1.2-ggx", "1.47-beckmann"]),
    },
    "tests/scattering/test_phong_lobes.py": {
        "test01_log1p_expm1_accuracy": (MORE, ["llvm_ad_rgb"]),
        "test02_samplers_match_their_densities": (MORE, [
            "mirror-normal-50.0", "mirror-grazing-1.0", "mirror-grazing-50.0",
            "halfway-normal-1.0", "halfway-normal-50.0", "halfway-grazing-1.0",
            "halfway-grazing-50.0"]),
    },
    "tests/scattering/test_thinfilm.py": {
        "test03_colour_equals_the_integrated_reference": DEEP,
    },
    "tests/test_bsdfspec.py": {
        "test01_every_entry_point_takes_every_form": (MORE, [
            "check_furnace", "check_energy", "albedo_curve", "check_stability"]),
        "test02_furnace_render_of_a_loaded_bsdf_in_jit": DEEP,
        "test07_every_command_takes_a_quoted_spec": (MORE, ["plot", "fit"]),
        "test08_a_check_loads_its_spec_once": DEEP,
    },
    "tests/test_compare.py": {
        "test02_identical_material_is_within_noise": DEEP,
        "test03_other_material_is_different": DEEP,
        "test05_cli_bad_input": (MORE, [
            "args1---swap expects ID=BSDF", "args2-no <bsdf id=\"nosuchid\">",
            "args3-the renders differ in size"]),
    },
    "tests/test_earth.py": {
        "test05_cli_plot_pp_and_the_furnace_white_sky": WHOLE,
        "test06_the_bundled_scene_renders": WHOLE,
    },
    "tests/test_fit.py": {
        "test01_round_trip": (MORE, [
            "phong", "cooktorrance", "ward", "orennayar", "ashikhmin", "lafortune",
            "cooktorrance-multiscatter", "he"]),
        "test03_blinn_phong_against_walters_mapping": DEEP,
        "test18_a_films_thickness_is_fitted": DEEP,
        "test04_schlick_r0_against_gold": DEEP,
        "test05_fitted_spec_is_written_as_the_spec_takes_it": DEEP,
        "test06_deterministic": DEEP,
        "test09_cli_writes_json": DEEP,
        "test10_cli_bad_input_exit_2_one_line": (MORE, [
            "args2-fit needs an RGB variant with automatic differentiation",
            "args5---model names 2 BSDFs; give one"]),
        "test11_useless_or_unphysical_fits_are_flagged": (MORE, [
            "at a bound", "more out than in"]),
        "test12_an_exact_fit_has_no_flag": DEEP,
        "test12b_grazing_pairs_do_not_make_a_good_fit_useless": DEEP,
        "test14_a_perfect_mirrors_index_is_fitted": DEEP,
    },
    "tests/test_fit_measured.py": {
        "test03_alpha_recovered_from_noisy_data": DEEP,
        "test08_models_all_cli": WHOLE,
        "test09_compare_published": WHOLE,
    },
    "tests/test_gallery.py": {
        "test03_quick_gallery": WHOLE,
    },
    "tests/test_presets.py": {
        "test04_each_preset_evaluates_bbms_model": (MORE, [
            "scalar_rgb-ward-gold-metallic-paint", "scalar_rgb-ward-blue-acrylic",
            "scalar_rgb-ward-nickel", "scalar_rgb-ward-white-diffuse-bball",
            "scalar_rgb-wardduer-gold-metallic-paint", "scalar_rgb-wardduer-blue-acrylic",
            "scalar_rgb-wardduer-nickel", "scalar_rgb-wardduer-white-diffuse-bball",
            "scalar_rgb-blinnphong-gold-metallic-paint", "scalar_rgb-blinnphong-blue-acrylic",
            "scalar_rgb-blinnphong-nickel", "scalar_rgb-blinnphong-white-diffuse-bball",
            "scalar_rgb-cooktorrance-gold-metallic-paint",
            "scalar_rgb-cooktorrance-blue-acrylic", "scalar_rgb-cooktorrance-nickel",
            "scalar_rgb-cooktorrance-white-diffuse-bball",
            "scalar_rgb-lafortune-gold-metallic-paint", "scalar_rgb-lafortune-blue-acrylic",
            "scalar_rgb-lafortune-nickel", "scalar_rgb-lafortune-white-diffuse-bball",
            "scalar_rgb-he-gold-metallic-paint", "scalar_rgb-he-blue-acrylic",
            "scalar_rgb-he-nickel", "scalar_rgb-he-white-diffuse-bball",
            "llvm_ad_rgb-lafortune-gold-metallic-paint", "llvm_ad_rgb-he-gold-metallic-paint",
            "llvm_ad_rgb-he-blue-acrylic", "llvm_ad_rgb-he-nickel",
            "llvm_ad_rgb-he-white-diffuse-bball"]),
        "test05_a_wrong_conversion_fails_the_check": (MORE, [
            "ward-form balanced", "wardduer-form original",
            "blinnphong-ks = A (no 4(n + 2^(-n/2))/(n + 4))", "blinnphong-the mirror lobe",
            "cooktorrance-ks = A (no 4/\\u03c0)",
            "cooktorrance-eta = F0 (a reflectance taken for an index)",
            "cooktorrance-Smith's masking", "lafortune-normalize false",
            "lafortune-cz = cxy (Phong's mirror lobe)", "he-sigma0 and tau swapped",
            "he-the holzschuch reading", "he-eta = 1.5", "he-no albedo"]),
        "test07_xml_and_dict_forms_are_the_same_bsdf": (MORE, ["scalar_rgb"]),
        "test12_the_plugins_reference_takes_the_preset": (MORE, [
            "phong-ngan:blue-acrylic", "cooktorrance-ngan:gold-metallic-paint",
            "lafortune-ngan:gold-metallic-paint"]),
        "test14_he_differs_from_bbm_in_its_blend_alone": DEEP,
    },
    "tests/test_readme.py": {
        "test01_python_blocks_run": (MORE, [
            "README.md#6", "docs/explore.md#0",  # (test_page: test08 calls mi_brdfs.explore)
            "docs/fit-and-simplify.md#1", "docs/presets.md#1",
            "docs/usage.md#0", "docs/validation.md#0"]),
    },
    "tests/test_reference_docs.py": {
        "test04_the_examples_on_each_page_load_and_agree": (MORE, ["he"]),
    },
    "tests/test_render.py": {
        "test09_time_budget_holds_with_processes": DEEP,
        "test12_helpers_kept_for_the_next_render": DEEP,
        "test13_kept_helpers_start_at_once_on_the_same_scene": DEEP,
    },
    "tests/test_runner.py": {
        "test01_a_signal_stops_the_threads_and_keeps_what_finished": (MORE, ["15"]),
    },
    "tests/test_simplify.py": {
        "test03_llvm_cli_report_nested_and_cache": WHOLE,
        "test05_bad_input_one_line_exit_2": (MORE, [
            "nobsdf.xml", "tiny.xml --report /proc/x", "tiny.xml -D spp=4",
            "tiny.xml -D res=0", "tiny.xml --confidence -1"]),
        "test07_speedup_bars_from_the_spread_of_repeats": DEEP,
        "test10b_included_files_left_alone_are_named": DEEP,
        "test10d_a_define_the_replacement_no_longer_references": DEEP,
        "test11_ashikhmin_and_lafortune_candidates": DEEP,
        "test21_simplicity_replaces_by_a_simpler_candidate_not_slower": (MORE, [
            "consistently-slower"]),
    },
    "tests/test_sweep.py": {
        "test01_pool_and_dask_give_one_table": WHOLE,
        "test02_the_cache_resumes": DEEP,
        "test04_cli": WHOLE,
        "test08_a_signal_stops_the_sweep_and_keeps_what_finished": (MORE, ["15"]),
    },
    "tests/test_testing.py": {
        "test01_each_assertion_passes_good_and_fails_broken": (MORE, [
            "assert_consistent", "assert_energy_conserving", "assert_albedo_matches_eval",
            "assert_furnace", "assert_gradients"]),
        "test07_defaults_judge_correct_bsdfs_as_the_battery": DEEP,
    },
    "tests/test_tutorial.py": {
        "test01_one_run_and_what_it_writes_and_prints": WHOLE,
    },
}
