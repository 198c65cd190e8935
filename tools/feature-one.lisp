;;;; tools/feature-one.lisp -- one process of make count-features (physics.org, #FBNCH9): load the
;;;; engine of the tree ROOT, build the feature scene NAME of +feature-scenes+ with every feature
;;;; (KIND general) or with the scene's own (KIND specialised), step it STEPS times, and print
;;;;   feature NAME KIND HASH
;;;; with the world's state hash.  As tools/against-one.lisp, it puts off every collection when
;;;; AGAINST_NURSERY_BYTES is set, for a collection's signals stop a program under valgrind.
;;;;
;;;; Usage: sbcl --script tools/feature-one.lisp ROOT/ NAME KIND STEPS

(let ((bytes (sb-ext:posix-getenv "AGAINST_NURSERY_BYTES")))
  (when (and bytes (plusp (length bytes)))
    (setf (sb-ext:bytes-consed-between-gcs) (parse-integer bytes))))

(defvar *feature-arguments* (rest sb-ext:*posix-argv*))

(unless (= 4 (length *feature-arguments*))
  (format *error-output* "feature-one: usage: feature-one.lisp ROOT/ NAME KIND STEPS~%")
  (sb-ext:exit :code 2))

(load (concatenate 'string (first *feature-arguments*) "tools/boot.lisp"))

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(destructuring-bind (root name kind steps) *feature-arguments*
  (declare (ignore root))
  (let* ((scene (intern (string-upcase name) :keyword))
         (entry (assoc scene (symbol-value (find-symbol "+FEATURE-SCENES+" :luv-physics))))
         (all (symbol-value (find-symbol "+PHYSICS-FEATURES+" :luv-physics)))
         (features (if (string-equal kind "specialised") (or (third entry) all) all)))
    (unless entry
      (format *error-output* "feature-one: no feature scene ~A~%" name)
      (sb-ext:exit :code 2))
    (multiple-value-bind (world before)
        (funcall (find-symbol "FEATURE-SCENE" :luv-physics) scene :features features)
      (dotimes (i (parse-integer steps))
        (when before (funcall before i))
        (funcall (find-symbol "STEP-PHYSICS-WORLD" :luv-physics) world))
      (format t "~&feature ~(~A~) ~(~A~) ~D~%" scene kind
              (funcall (find-symbol "PHYSICS-WORLD-STATE-HASH" :luv-physics) world))
      (finish-output))))
