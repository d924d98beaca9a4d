; Initial state W0 and goal of Table 8.2. Zones: the recovery zone is the
; origin (Extract 7.7); the cable lies in the inspection zone.
(define (problem cable-tracking-mission)
  (:domain cable-tracking)
  (:objects auv - robot
            deploy recovery - zone
            cable - target)
  (:init
    (position_bad auv) (surface auv) (no_alarms auv) (in auv deploy)
    (not_found cable) (not_mapped cable)
    (= (x deploy) 5) (= (y deploy) 0)
    (= (x inspection) 45) (= (y inspection) 30)
    (= (x recovery) 0) (= (y recovery) 0)
    (= (distance deploy inspection) 50) (= (distance inspection deploy) 50)
    (= (distance inspection recovery) 54) (= (distance recovery inspection) 54)
    (= (distance deploy recovery) 5) (= (distance recovery deploy) 5)
    (= (altitude auv) 1.5) (= (dive_timeout auv) 60) (= (search_timeout auv) 300)
    (= (description cable) "cable") (= (params_nac cable) "nac"))
  (:goal (and (surface auv) (in auv recovery) (mapped cable)))
  (:metric minimize (total-cost)))
