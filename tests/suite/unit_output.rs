//! Unit tests of `src/output/`: the URDF export's numbers and angles, and the plots.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod plot {
    use lsdc::output::plot::*;
    use lsdc::simulate::run::{Report, Sample, Simulation};

    fn simulation(count: usize, conservative: bool) -> Simulation {
        let samples = (0..count)
            .map(|k| {
                let t = k as f64 * 0.05;
                let (angle, rate) = (0.8 * (2.0 * t).cos(), -1.6 * (2.0 * t).sin());
                let (slide, slide_rate) = (0.3 * (3.0 * t).sin() + 0.2, 0.9 * (3.0 * t).cos());
                let kinetic = 0.5 * rate * rate + 0.5 * slide_rate * slide_rate;
                Sample {
                    time: t,
                    coordinates: vec![angle, slide],
                    rates: vec![rate, slide_rate],
                    kinetic_energy: kinetic,
                    potential_energy: conservative.then_some(2.0 - kinetic + 0.01 * t),
                    work: None,
                    balance: None,
                    momentum: [0.0; 6],
                    reactions: Vec::new(),
                    outputs: Vec::new(),
                }
            })
            .collect();
        Simulation {
            coordinate_names: vec!["crank.q".to_string(), "slider.x".to_string()],
            reaction_names: Vec::new(),
            output_names: Vec::new(),
            samples,
            report: Report {
                steps: count,
                function_evaluations: 4 * count,
                ..Report::empty("rk4", (count.max(1) - 1) as f64 * 0.05)
            },
        }
    }

    fn temp_path(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("lsdc-plot-{}-{name}", std::process::id()))
    }

    #[test]
    fn renders_svg_and_png() {
        let simulation = simulation(201, true);
        let svg = temp_path("test.svg");
        plot(&simulation, &svg).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with(&format!(
            "<svg width=\"{WIDTH}\" height=\"{HEIGHT}\" viewBox="
        )));
        for name in &simulation.coordinate_names {
            assert!(text.contains(name.as_str()), "the SVG names {name}");
        }
        assert!(text.contains("total (kinetic + potential)"));

        let png = temp_path("test.png");
        plot(&simulation, &png).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.len() > 1000);
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        std::fs::remove_file(svg).unwrap();
        std::fs::remove_file(png).unwrap();
    }

    #[test]
    fn the_programs_named_outputs_are_plotted() {
        let mut simulation = simulation(101, true);
        simulation.output_names = vec!["tip_height".to_string()];
        for sample in &mut simulation.samples {
            sample.outputs = vec![1.5 * sample.coordinates[0].sin()];
        }
        let svg = temp_path("outputs.svg");
        plot(&simulation, &svg).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        std::fs::remove_file(svg).unwrap();
        assert!(text.contains("tip_height"), "the legend names the output");
        assert!(text.contains("Coordinates and outputs"));
        // Its line: one polyline more than the run without outputs draws.
        let without = temp_path("no-outputs.svg");
        plot(&self::simulation(101, true), &without).unwrap();
        let plain = std::fs::read_to_string(&without).unwrap();
        std::fs::remove_file(without).unwrap();
        assert!(text.matches("<polyline").count() > plain.matches("<polyline").count());
    }

    #[test]
    fn degenerate_runs_still_plot() {
        // One output, no potential: every range is a single value.
        let path = temp_path("single.png");
        plot(&simulation(1, false), &path).unwrap();
        assert!(std::fs::metadata(&path).unwrap().len() > 0);
        std::fs::remove_file(path).unwrap();
    }

    #[test]
    fn tick_labels_tell_the_ticks_apart() {
        let axis = Axis::new([-1.05, 1.05].into_iter(), false);
        assert_eq!((axis.offset, &axis.format), (0.0, &LabelFormat::Fixed(1)));
        assert_eq!(axis.label(-1e-17), "0.0");
        assert_eq!(axis.label(-0.4), "-0.4");
        assert_eq!(
            Axis::new([0.0, 4500.0].into_iter(), false).label(500.0),
            "500"
        );
        assert_eq!(
            Axis::new([0.0, 2e-6].into_iter(), false).label(1e-6),
            "1.0e-6"
        );
        // A conserved energy that drifts by parts in 10¹²: labelled relative to an offset.
        let axis = Axis::new([4.005_2, 4.005_2 + 3e-11].into_iter(), true);
        assert_eq!(axis.description("energy"), "energy − 4.0052");
        assert!(axis.range.start > -1e-10 && axis.range.end < 1e-10);
        assert_eq!(axis.label(2e-11), "2.0e-11");
        assert_eq!(axis.label(-8e-28), "0");
        let axis = Axis::new([-2.96, -2.96 - 1e-9].into_iter(), true);
        assert!(
            axis.description("energy").starts_with("energy + 2.96"),
            "{}",
            axis.description("energy")
        );
        // Constant or missing values still get a range.
        assert_eq!(Axis::new([3.0, 3.0].into_iter(), true).range, 0.0..6.0);
        assert_eq!(Axis::new(std::iter::empty(), true).range, -1.0..1.0);
    }

    /// `--plot-columns`: the chosen columns, a panel per group captioned with their names, and
    /// nothing else (no other coordinate, no energy panel); a column's values are the samples'
    /// (a rate, an energy); a misspelt name is refused with the closest column.
    #[test]
    fn chosen_columns_are_plotted_alone() {
        use lsdc::output::plot_columns::{resolve, UnknownColumn};
        let simulation = simulation(101, true);
        let groups = [
            "crank.q, slider.x'".to_string(),
            "kinetic_energy".to_string(),
        ];
        let panels = resolve(&simulation.coordinate_names, &[], &groups).unwrap();
        let names: Vec<Vec<&str>> = (panels.iter())
            .map(|p| p.iter().map(|c| c.name.as_str()).collect())
            .collect();
        assert_eq!(
            names,
            [vec!["crank.q", "slider.x'"], vec!["kinetic_energy"]]
        );
        let sample = &simulation.samples[7];
        assert_eq!(panels[0][1].value(sample), Some(sample.rates[1]));
        assert_eq!(panels[1][0].value(sample), Some(sample.kinetic_energy));
        let svg = temp_path("columns.svg");
        plot_columns(&simulation, &svg, &panels).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        std::fs::remove_file(svg).unwrap();
        // The SVG's texts (a line each): the captions, the legends, the axes' labels.
        let texts: Vec<&str> = text.lines().filter(|l| !l.starts_with('<')).collect();
        let count = |wanted: &str| texts.iter().filter(|&&t| t == wanted).count();
        assert_eq!(count("crank.q, slider.x&apos;"), 1, "a caption");
        assert_eq!(count("kinetic_energy"), 2, "a caption and a legend");
        assert_eq!(
            (count("crank.q"), count("slider.x&apos;")),
            (1, 1),
            "legends"
        );
        assert_eq!(
            (count("slider.x"), count("Energy"), count("kinetic")),
            (0, 0, 0)
        );
        let misspelt = ["crank.q,slider.y".to_string()];
        let unknown = resolve(&simulation.coordinate_names, &[], &misspelt).unwrap_err();
        let expected = UnknownColumn {
            name: "slider.y".to_string(),
            suggestion: Some("slider.x".to_string()),
        };
        assert_eq!(unknown, expected);
    }

    #[test]
    fn rejects_other_extensions_and_empty_runs() {
        let error = plot(&simulation(3, true), &temp_path("plot.pdf"))
            .unwrap_err()
            .to_string();
        assert!(error.contains(".svg") && error.contains(".png"), "{error}");
        assert!(plot(&simulation(3, true), &temp_path("plot")).is_err());
        assert!(plot(&simulation(0, true), &temp_path("empty.svg")).is_err());
    }
}

mod urdf {
    use lsdc::diag::number::shortest as number;
    use lsdc::output::urdf::*;
    use nalgebra::UnitQuaternion;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn roll_pitch_yaw_give_back_the_rotation_near_gimbal_lock() {
        for pitch in [
            0.3,
            FRAC_PI_2 - 1e-7,
            FRAC_PI_2,
            -FRAC_PI_2 + 1e-9,
            -FRAC_PI_2,
        ] {
            let rotation = UnitQuaternion::from_euler_angles(0.7, pitch, -2.1);
            let [r, p, y] = rpy(&rotation);
            let back = UnitQuaternion::from_euler_angles(r, p, y);
            assert!(
                rotation.angle_to(&back) < 1e-15,
                "pitch {pitch}: {}",
                rotation.angle_to(&back)
            );
        }
    }

    #[test]
    fn numbers_read_back_exactly() {
        for x in [
            0.0,
            -0.0,
            1.0,
            -0.4,
            0.1 + 0.2,
            1.0 / 12.0,
            6.123e-17,
            1e16,
            -1e300,
            12345.678,
        ] {
            assert_eq!(number(x).parse::<f64>(), Ok(x + 0.0), "{x}");
        }
        assert_eq!(
            [number(-0.0), number(0.5), number(6e-17), number(NO_LIMIT)],
            ["0", "0.5", "6e-17", "1e16"]
        );
    }
}
